"""A presentation built once for every planner that meets it, inside one worker process.

Every planner of a protocol meets the same presentation (the trial seed does not depend on the
planner), and a benchmark runs a presentation's planners one after another in one worker
(:mod:`hsqbench.experiment.executor`). What comes before the first plan is the same for all of
them: the compiled and settled scene, the cameras' renderers, the first observation, the true
hulls and the graspability search. :class:`PresentationCache` keeps the last presentation of
the process and hands it to the next trial with the same kind, objects, seed and config (the
same config object), so that work is done once; every trial then starts from the same state as
a freshly built one:

- the data is new and reset to the settled keyframe (as a build ends);
- the model fields a trial may change (``TrialEnv.remove``, the no-slip setting) are put back;
- the first observation, true hulls and graspability are handed out as copies, with the random
  streams they drew from set to where drawing them left them, and the same ``mj_forward`` and
  ``mj_kinematics`` calls made on the data as computing them would make.

So outcomes are the same as with a build per trial (``tests/test_trial_presentation.py``). The
first look's ``perception_s`` is the one measured when it was made. A trial with an enabled
recorder builds its own scene (the recorder sees the build).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from hsqbench.sim.objects import ObjectLike


@dataclass
class Look:
    """What an attempt perceives and learns before planning: the cloud (``obs``) and the
    seconds perceiving took, the true hulls of the objects on the table, and those the oracle
    can grasp (None: the check is off)."""

    obs: Any
    perception_s: float
    truth: Any
    graspable: list[str] | None


@dataclass
class FirstLook:
    """A presentation's first :class:`Look` and the random streams' states after it (stream
    name -> ``bit_generator.state``)."""

    look: Look
    states: dict[str, dict]


@dataclass
class Presentation:
    """A built scene kept for the next planner: model, info, assets, the cameras' sensor and
    the model fields a trial may change, as built."""

    key: tuple
    config: Any
    model: mujoco.MjModel
    info: Any
    assets: dict[str, ObjectLike]
    sensor: Any = None
    first_look: FirstLook | None = None

    def __post_init__(self) -> None:
        m = self.model
        self._pristine = {
            "body_gravcomp": m.body_gravcomp.copy(),
            "geom_contype": m.geom_contype.copy(),
            "geom_conaffinity": m.geom_conaffinity.copy(),
        }
        self._noslip = int(m.opt.noslip_iterations)

    def fresh_data(self) -> mujoco.MjData:
        """The model as built and a new data at the settled state (as a build returns them)."""
        m = self.model
        for name, value in self._pristine.items():
            np.copyto(getattr(m, name), value)
        m.opt.noslip_iterations = self._noslip
        data = mujoco.MjData(m)
        self.info.reset(m, data)
        return data

    def close(self) -> None:
        if self.sensor is not None and hasattr(self.sensor, "close"):
            self.sensor.close()
        self.sensor = None


def _names(objects: Any) -> tuple[str, ...] | None:
    """The objects' names when they are all library names (only those are cached)."""
    if objects is None:
        return None
    items = [objects] if isinstance(objects, str) else list(objects)
    return tuple(items) if all(isinstance(o, str) for o in items) else None


class PresentationCache:
    """The process's last presentation (one: a worker runs a presentation's planners in a row)."""

    def __init__(self) -> None:
        self._entry: Presentation | None = None

    @staticmethod
    def key(kind: str, objects: Any, seed: int) -> tuple | None:
        names = _names(objects)
        return None if names is None else (kind, names, int(seed))

    def get(self, key: tuple | None, config: Any) -> Presentation | None:
        entry = self._entry
        if key is None or entry is None or entry.key != key or entry.config is not config:
            return None
        return entry

    def put(self, entry: Presentation) -> None:
        self.clear()
        self._entry = entry

    def clear(self) -> None:
        if self._entry is not None:
            self._entry.close()
        self._entry = None


#: The cache of this process.
CACHE = PresentationCache()


def copied(value: Any) -> Any:
    """A deep copy: a planner may change its input in place without touching the next one's."""
    return copy.deepcopy(value)
