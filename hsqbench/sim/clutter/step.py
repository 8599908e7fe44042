"""One look and plan of a clutter-removal step, shared by the hand's round
(:mod:`hsqbench.sim.clutter.round`) and the arm's (:mod:`hsqbench.sim.clutter.arm`)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hsqbench.planner.failure import PlannerError, checked_plan
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult
from hsqbench.sim.trial.attempt import plan_fields

#: Independent random streams drawn from a round's seed (the scene has the seed itself).
STREAMS = ("perception_calibration", "perception_noise", "planner", "oracle")


def round_streams(seed: int) -> dict[str, np.random.Generator]:
    """The round's random streams (:data:`STREAMS`), the same for the hand and the arm."""
    streams = np.random.SeedSequence([seed, 1]).spawn(len(STREAMS))
    return {n: np.random.default_rng(s) for n, s in zip(STREAMS, streams, strict=True)}


@dataclass
class RoundTally:
    """What a round has done so far, kept the same way by the hand's round and the arm's."""

    attempts: list[Attempt] = field(default_factory=list)
    cleared: list[str] = field(default_factory=list)
    lost: list[str] = field(default_factory=list)

    @property
    def outcomes(self) -> list[str]:
        """The attempts' outcomes in order, as the stop rule reads them."""
        return [a.outcome.value for a in self.attempts]

    def record(self, attempt: Attempt) -> None:
        self.attempts.append(attempt)
        if attempt.outcome == Outcome.SUCCESS:
            self.cleared.append(attempt.target)

    def lose(self, attempt: Attempt, gone: list[str]) -> None:
        """``gone`` left the workspace after ``attempt``: taken out, not cleared."""
        self.lost += gone
        for n in gone:
            attempt.detail += f"; {n} left the workspace (taken out, not cleared)"

    def result(
        self, objects: list[str], unplaced: list[str], seed: int, planner: Any
    ) -> RoundResult:
        """The round's result; ``planner`` a name or a planner."""
        name = planner if isinstance(planner, str) else str(getattr(planner, "name", planner))
        return RoundResult(
            objects=objects,
            seed=seed,
            planner=name,
            attempts=self.attempts,
            objects_cleared=self.cleared,
            objects_graspable=None,
            objects_lost=self.lost,
            objects_unplaced=unplaced,
        )


@dataclass
class Planned:
    """A look and a plan: ``ended`` when the step ends without a grasp (too few points, no
    grasp, the planner's own error), else the planner's ``grasps`` and what every attempt
    records (``common``)."""

    ended: Attempt | None
    grasps: Sequence[Any] = ()
    points: Any = None
    common: dict[str, Any] = field(default_factory=dict)


def plan_step(
    obs: Any,
    perception_s: float,
    planner: Any,
    kind: str,
    config: Any,
    seed: int,
    support_plane: Any,
    truth: Callable[[], Any],
) -> Planned:
    """Plan on one observation as their loop does (the cloud, the depth images, the table plane
    and the workspace; ``truth`` is called for a privileged planner only)."""
    from hsqbench.planner.api import PlanningContext

    points = np.asarray(obs.points)
    privileged = getattr(planner, "privileged", False)
    if len(points) < config.min_cloud_points and not privileged:
        detail = f"the cloud has {len(points)} points (fewer than {config.min_cloud_points})"
        return Planned(Attempt(Outcome.NO_GRASP_FOUND, perception_s=perception_s, detail=detail))
    context = PlanningContext(
        support_plane=tuple(float(x) for x in support_plane),
        packed=True,
        seed=seed,
        camera_positions=np.asarray(obs.camera_positions),
        workspace_bounds=(obs.workspace_min, obs.workspace_max),
        truth=truth() if privileged else None,
        scene=kind,
        depth_views=getattr(obs, "cameras", None),
    )
    t1 = time.perf_counter()
    try:
        plan = checked_plan(planner, points, context)
    except PlannerError as exc:  # the planner's own failure: a failed attempt without a grasp
        planning_s = time.perf_counter() - t1
        return Planned(
            Attempt(
                Outcome.PLANNER_ERROR,
                perception_s=perception_s,
                planning_s=planning_s,
                detail=str(exc),
            )
        )
    planning_s = time.perf_counter() - t1
    grasps = plan.grasps
    common = plan_fields(plan, perception_s, planning_s, config.recorded_scores)
    if not len(grasps):
        detail = plan.reason or "the planner returned no grasp"
        return Planned(Attempt(Outcome.NO_GRASP_FOUND, detail=detail, **common))
    return Planned(None, grasps, points, common)
