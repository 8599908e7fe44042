"""The trial list of a protocol, and each trial's seed.

Seed derivation (documented contract; changing it changes every result):

    seed = int.from_bytes(sha256(f"{base_seed}|{experiment}|{object}|{index}").digest()[:4], "big")
           & 0x7FFFFFFF

- isolated trial ``index`` (0-based) of ``object``: ``object`` is the object name;
- packed round ``index``: ``object`` is ``"round"``; the round's objects are drawn, without
  replacement and listed in the order of ``packed.objects``, by
  ``np.random.default_rng(derive_seed(base_seed, "packed", "draw", index))``. When a placement
  check is given (the backend's ``placeable``), a draw that cannot be placed apart with the
  round's seed is rejected and the *same* generator draws again, up to ``packed.max_draws``
  draws; the first draw is unchanged, so rounds that were placeable keep their objects.
- pile round ``index``: the same with ``experiment`` = ``"pile"`` (its own seeds and draws), and
  the pile check (the backend's ``pile_placeable``: the pile settles on the table) in place of
  the placement check.

The planner is deliberately *not* part of the seed: every planner meets the same poses and the
same rounds, so planners are compared on paired trials. Seeds are 31-bit so that any consumer
(NumPy, MuJoCo, int32 fields) accepts them. A trial's identity is its :attr:`TrialSpec.key`.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from hsqbench.experiment.config import EXPERIMENTS, ExperimentConfig

Experiment = Literal["isolated", "packed", "pile"]

#: Whether a packed draw can be placed apart: ``(objects, round seed) -> bool``.
Placeable = Callable[[tuple[str, ...], int], bool]


def derive_seed(base_seed: int, experiment: str, obj: str, index: int) -> int:
    """The 31-bit seed of one trial (see the module docstring)."""
    if base_seed < 0 or index < 0:
        raise ValueError(f"base_seed and index must be >= 0, got {base_seed}, {index}")
    blob = f"{base_seed}|{experiment}|{obj}|{index}".encode()
    return int.from_bytes(hashlib.sha256(blob).digest()[:4], "big") & 0x7FFFFFFF


@dataclass(frozen=True)
class TrialSpec:
    """One unit of work: an isolated trial (one object) or a packed round (several objects)."""

    experiment: Experiment
    planner: str
    base_seed: int
    index: int
    objects: tuple[str, ...]
    seed: int
    rejected_draws: tuple[tuple[str, ...], ...] = ()

    @property
    def draw_note(self) -> str:
        """How a packed round's objects were drawn, in words, when not by the first draw."""
        if not self.rejected_draws:
            return ""
        listed = " | ".join(";".join(d) for d in self.rejected_draws)
        why = (
            "did not settle into a pile"
            if self.experiment == "pile"
            else "could not be placed apart"
        )
        return f"redrawn: {len(self.rejected_draws)} draw(s) {why} and were replaced ({listed})"

    @property
    def key(self) -> str:
        """Unique, stable identity of the trial within a run (used for resume and dedup)."""
        if self.experiment == "isolated":
            where = f"{self.objects[0]}/{self.index:03d}"
        else:
            where = f"round/{self.index:03d}"
        return f"{self.experiment}/{self.planner}/s{self.base_seed}/{where}"


class PackedDrawError(ValueError):
    """No draw of a packed round could be placed within ``packed.max_draws`` draws."""


@dataclass(frozen=True)
class PackedDraw:
    """The objects of a packed round and the draws rejected before them (in draw order)."""

    objects: tuple[str, ...]
    rejected: tuple[tuple[str, ...], ...] = ()


def _draw(rng: np.random.Generator, pool: tuple[str, ...], per_round: int) -> tuple[str, ...]:
    chosen = np.sort(rng.choice(len(pool), size=per_round, replace=False))
    return tuple(pool[i] for i in chosen)


def packed_round_objects(
    pool: tuple[str, ...], per_round: int, base_seed: int, index: int
) -> tuple[str, ...]:
    """The first draw of packed round ``index``: ``per_round`` distinct objects of ``pool``."""
    rng = np.random.default_rng(derive_seed(base_seed, "packed", "draw", index))
    return _draw(rng, pool, per_round)


def draw_packed_round(
    pool: tuple[str, ...],
    per_round: int,
    base_seed: int,
    index: int,
    placeable: Placeable | None = None,
    max_draws: int = 1,
    experiment: str = "packed",
) -> PackedDraw:
    """The objects of packed round ``index``: the first draw that ``placeable`` accepts.

    Draws come one after another from the round's generator (see the module docstring);
    ``placeable`` is asked with the round's seed, the seed its scene is built with, so an
    accepted draw is one the scene builder places. ``None`` accepts the first draw.
    ``experiment``: ``"packed"`` or ``"pile"``, whose rounds have seeds of their own.

    Raises:
        PackedDrawError: none of ``max_draws`` draws is placeable.
    """
    if max_draws < 1:
        raise ValueError(f"max_draws must be >= 1, got {max_draws}")
    rng = np.random.default_rng(derive_seed(base_seed, experiment, "draw", index))
    seed = derive_seed(base_seed, experiment, "round", index)
    rejected: list[tuple[str, ...]] = []
    for _ in range(max_draws):
        objects = _draw(rng, pool, per_round)
        # A set drawn again gets the same answer (same seed): no second check.
        if objects not in rejected and (placeable is None or placeable(objects, seed)):
            return PackedDraw(objects, tuple(rejected))
        rejected.append(objects)
    fails = "settle into a pile on the table" if experiment == "pile" else "be placed apart"
    raise PackedDrawError(
        f"{experiment} round {index} (base seed {base_seed}): none of {max_draws} draws of "
        f"{per_round} objects can {fails} in the workspace (first: {';'.join(rejected[0])}); "
        f"raise {experiment}.max_draws, lower {experiment}.objects_per_round, or enlarge "
        "workspace.size_m in the scene config"
    )


def build_trials(
    config: ExperimentConfig,
    planners: Iterable[str] | None = None,
    experiments: Iterable[str] | None = None,
    placeable: Placeable | None = None,
    pile_placeable: Placeable | None = None,
) -> list[TrialSpec]:
    """Every trial of ``config``, optionally restricted to some planners and experiments.

    The order is deterministic: base seed, then trial, then planner, so that a partial run has
    covered all planners on the same trials (paired data), and the packed rounds come after the
    isolated trials of the same seed. Each packed round is drawn once, here, for all planners
    (:func:`draw_packed_round` with ``placeable``, the backend's placement check; None: no
    check, the first draw); pile rounds likewise with ``pile_placeable``.

    Raises:
        ValueError: a requested planner or experiment is not in the config (or is disabled).
        PackedDrawError: a packed round has no placeable draw within ``packed.max_draws``.
    """
    planners = tuple(config.planners if planners is None else planners)
    unknown = [p for p in planners if p not in config.planners]
    if unknown:
        raise ValueError(
            f"planner(s) {unknown} are not in this config's planners {list(config.planners)}; "
            "add them to the config (a new config means a new run)"
        )
    enabled = config.enabled_experiments()
    experiments = tuple(enabled if experiments is None else experiments)
    for exp in experiments:
        if exp not in EXPERIMENTS:
            raise ValueError(f"unknown experiment {exp!r}; choose from {list(EXPERIMENTS)}")
        if exp not in enabled:
            raise ValueError(f"experiment {exp!r} is disabled in this config")

    specs: list[TrialSpec] = []
    for base in config.seeds:
        if "isolated" in experiments:
            iso = config.isolated
            for obj in iso.objects:
                for i in range(iso.attempts_per_object):
                    seed = derive_seed(base, "isolated", obj, i)
                    specs.extend(TrialSpec("isolated", p, base, i, (obj,), seed) for p in planners)
        for exp, check in (("packed", placeable), ("pile", pile_placeable)):
            if exp not in experiments:
                continue
            pk = getattr(config, exp)
            for i in range(pk.rounds):
                draw = draw_packed_round(
                    pk.objects, pk.objects_per_round, base, i, check, pk.max_draws, exp
                )
                seed = derive_seed(base, exp, "round", i)
                specs.extend(
                    TrialSpec(exp, p, base, i, draw.objects, seed, draw.rejected) for p in planners
                )
    return specs
