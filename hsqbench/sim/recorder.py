"""Hook for recording an episode (the Rerun episode viewer implements it).

The trial runner calls a :class:`Recorder` at fixed points of every attempt:

1. ``on_scene(model, data, info)``: once per trial or round, after the scene is built and settled.
2. ``on_observation(observation)``: the perceived cloud (``hsqbench.sim.perception.PerceivedCloud``
   or the trial runner's stand-in with the same ``points`` and ``camera_positions``).
3. ``on_plan(plan)``: the planner's :class:`~hsqbench.planner.api.PlanResult`.
4. ``on_grasp(grasp, rank)``: the grasp about to be executed (``Grasp``, 0-based rank).
5. ``on_step(model, data, phase)``: during execution, every ``step_interval_s`` of simulated
   time; ``phase`` names the motion (``pregrasp``, ``approach``, ``close``, ``lift``, ``carry``,
   ``release``, ``home``).
6. ``on_outcome(attempt)``: the attempt's :class:`~hsqbench.sim.outcome.Attempt`.

A recorder with ``enabled = False`` is never called during stepping, and the runner builds
nothing for it, so :class:`NullRecorder` (the default) costs nothing. Recorders must not change
the simulation: the same seed gives the same result with and without one.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import mujoco


@runtime_checkable
class Recorder(Protocol):
    """What the trial runner calls; see the module docstring for when."""

    enabled: bool
    step_interval_s: float

    def on_scene(self, model: mujoco.MjModel, data: mujoco.MjData, info: Any) -> None: ...

    def on_observation(self, observation: Any) -> None: ...

    def on_plan(self, plan: Any) -> None: ...

    def on_grasp(self, grasp: Any, rank: int) -> None: ...

    def on_step(self, model: mujoco.MjModel, data: mujoco.MjData, phase: str) -> None: ...

    def on_outcome(self, attempt: Any) -> None: ...


class NullRecorder:
    """Records nothing (the default)."""

    enabled = False
    step_interval_s = 0.0

    def on_scene(self, model: mujoco.MjModel, data: mujoco.MjData, info: Any) -> None:
        return None

    def on_observation(self, observation: Any) -> None:
        return None

    def on_plan(self, plan: Any) -> None:
        return None

    def on_grasp(self, grasp: Any, rank: int) -> None:
        return None

    def on_step(self, model: mujoco.MjModel, data: mujoco.MjData, phase: str) -> None:
        return None

    def on_outcome(self, attempt: Any) -> None:
        return None
