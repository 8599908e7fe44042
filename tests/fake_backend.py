"""A fast, deterministic stand-in for the simulation backend, for tests and runner benchmarks.

It simulates nothing: each attempt succeeds with a planner's probability, drawn from
``np.random.default_rng(seed)``, so the same trial always gives the same record. Its knobs make
the infrastructure's failure paths reachable: trials that raise, trials that kill their worker
process, and a run interrupted after some number of trials. Its records say ``detail="fake"``;
results made with it mean nothing about grasping.
"""

from __future__ import annotations

import dataclasses
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hsqbench.sim.outcome import Attempt, Outcome, RoundResult, TrialResult
from hsqbench.sim.stop_rule import PackedConfig

_FAILURES = (
    Outcome.NO_GRASP_FOUND,
    Outcome.UNREACHABLE,
    Outcome.COLLISION_ON_APPROACH,
    Outcome.EMPTY_GRASP,
    Outcome.DROPPED,
)


@dataclass
class FakeBackend:
    """Attributes:
    success: per-planner success probability (``default_success`` for others).
    raise_on: objects (or ``"round"`` for packed rounds) whose trials raise ``RuntimeError``.
    exit_on: objects whose trials end their process with ``os._exit(3)`` (a worker crash).
    interrupt_after: raise ``KeyboardInterrupt`` at the start of this process's n-th call
        (0-based count of calls), to stop a run part way.
    sleep_s: seconds each trial waits, to make a run long enough to kill.
    unplaceable: groups of objects that cannot be placed together: a packed draw holding all
        objects of a group is refused by :meth:`placeable` (and raises if run anyway).
    unbuildable: objects that :meth:`prepare` reports as unusable (and whose trials raise).
    unknown: objects that :meth:`prepare` does not know (it raises ``ValueError``).
    broken: planners whose every attempt ends in their own error (``planner_error``).
    """

    success: dict[str, float] = field(default_factory=dict)
    default_success: float = 0.8
    raise_on: tuple[str, ...] = ()
    exit_on: tuple[str, ...] = ()
    interrupt_after: int | None = None
    sleep_s: float = 0.0
    unplaceable: tuple[tuple[str, ...], ...] = ()
    unbuildable: tuple[str, ...] = ()
    unknown: tuple[str, ...] = ()
    broken: tuple[str, ...] = ()
    name: str = "fake"
    stop_rule: PackedConfig = field(default_factory=PackedConfig)

    def __post_init__(self) -> None:
        self._calls = 0
        self.prepared: tuple[str, ...] = ()  # what the last prepare() was asked for

    def fingerprint(self) -> dict[str, Any]:
        return {
            "backend": self.name,
            "success": dict(sorted(self.success.items())),
            "default_success": self.default_success,
            "unplaceable": [list(g) for g in self.unplaceable],
            # Where the report finds the stop rule (a sim run has it in its trial config).
            "packed": dataclasses.asdict(self.stop_rule),
        }

    def check(self, planners: tuple[str, ...]) -> None:
        return None

    def prepare(self, objects: tuple[str, ...], jobs: int | None, progress: bool) -> dict[str, str]:
        self.prepared = tuple(objects)
        unknown = [o for o in objects if o in self.unknown]
        if unknown:
            raise ValueError(f"unknown object(s) {unknown}")
        return {
            o: "fake backend: this mesh cannot be built" for o in objects if o in self.unbuildable
        }

    def placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        if set(objects) & set(self.unbuildable):
            raise AssertionError(f"placeable asked about unbuildable objects {objects}")
        return not any(set(group) <= set(objects) for group in self.unplaceable)

    def pile_placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        """As :meth:`placeable`: ``unplaceable`` groups do not pile either."""
        return self.placeable(objects, seed)

    def _enter(self, what: tuple[str, ...]) -> None:
        if self.interrupt_after is not None and self._calls >= self.interrupt_after:
            raise KeyboardInterrupt(f"fake backend interrupted after {self._calls} calls")
        self._calls += 1
        if self.sleep_s > 0:
            time.sleep(self.sleep_s)
        if any(w in self.exit_on for w in what):
            os._exit(3)
        if any(w in self.raise_on or w in self.unbuildable for w in what):
            raise RuntimeError(f"fake backend failure for {what}")

    def _attempt(self, rng: np.random.Generator, planner: str, target: str) -> Attempt:
        if planner in self.broken:
            return Attempt(Outcome.PLANNER_ERROR, detail=f"fake: planner {planner!r} raised")
        p = self.success.get(planner, self.default_success)
        ok = bool(rng.random() < p)
        outcome = Outcome.SUCCESS if ok else _FAILURES[int(rng.integers(len(_FAILURES)))]
        factors = {k: float(rng.uniform(0.1, 1.0)) for k in ("h_alpha", "h_beta", "h_gamma")}
        factors["h_delta"] = float(rng.uniform(0.1, 1.0))
        return Attempt(
            outcome=outcome,
            target=target if outcome != Outcome.NO_GRASP_FOUND else "",
            rank_executed=0 if outcome != Outcome.NO_GRASP_FOUND else -1,
            n_grasps=int(rng.integers(1, 200)) if outcome != Outcome.NO_GRASP_FOUND else 0,
            score=float(np.prod(list(factors.values()))),
            factors=factors,
            width_m=float(rng.uniform(0.01, 0.08)),
            perception_s=float(rng.uniform(0.05, 0.1)),
            planning_s=float(rng.lognormal(0.0, 0.3)),
            execution_s=float(rng.uniform(2.0, 4.0)),
            detail="fake",
        )

    def run_isolated(self, obj: str, seed: int, planner: str) -> TrialResult:
        self._enter((obj,))
        rng = np.random.default_rng(seed)
        return TrialResult(obj, seed, planner, [self._attempt(rng, planner, obj)])

    def run_packed(self, objects: list[str], seed: int, planner: str) -> RoundResult:
        """A round under the trial runner's stop rule (:mod:`hsqbench.sim.stop_rule`)."""
        self._enter(("round", *objects))
        if not self.placeable(tuple(objects), seed):
            raise ValueError(f"fake backend: could not place {objects} without contact")
        rng = np.random.default_rng(seed)
        left = list(objects)
        attempts: list[Attempt] = []
        cleared: list[str] = []
        while self.stop_rule.stop_reason([a.outcome.value for a in attempts], bool(left)) is None:
            target = left[int(rng.integers(len(left)))]
            attempt = self._attempt(rng, planner, target)
            attempts.append(attempt)
            if attempt.success:
                left.remove(target)
                cleared.append(target)
        return RoundResult(list(objects), seed, planner, attempts, cleared)

    def run_pile(self, objects: list[str], seed: int, planner: str) -> RoundResult:
        """A pile round: the packed rule on the same fake draws."""
        return self.run_packed(objects, seed, planner)
