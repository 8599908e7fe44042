"""What one grasp attempt, one isolated trial and one packed round produce.

These records are the contract between the trial runner (``hsqbench.sim.trial``) and the
experiment code (``hsqbench.experiment``): one CSV row per attempt and one per packed round.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from enum import StrEnum
from typing import Any

#: Fields of :class:`Attempt` that measure the machine (wall-clock seconds), not the trial: two
#: runs of one seed differ in these only.
WALL_CLOCK_FIELDS = (
    "perception_s",
    "planning_s",
    "execution_s",
    "motion_planning_s",
    "planner_stages_s",
)


class Outcome(StrEnum):
    """The fixed list of attempt outcomes. ``planner_error``: the planner raised or returned
    something its contract rules out (not a PlanResult, an invalid Grasp); a failed attempt of
    that planner, as ``no_grasp_found`` is (:mod:`hsqbench.planner.failure`)."""

    SUCCESS = "success"
    NO_GRASP_FOUND = "no_grasp_found"
    PLANNER_ERROR = "planner_error"
    UNREACHABLE = "unreachable"
    COLLISION_ON_APPROACH = "collision_on_approach"
    EMPTY_GRASP = "empty_grasp"
    DROPPED = "dropped"
    SIM_UNSTABLE = "sim_unstable"


@dataclass
class Attempt:
    """One grasp attempt.

    Attributes:
        outcome: one of :class:`Outcome`.
        target: name of the object grasped (or the object that was meant, for failures; ``""``
            when no grasp was found).
        rank_executed: 0-based rank of the executed grasp in the planner's list (-1 if none).
        n_grasps: number of grasps the planner returned.
        score: score of the executed grasp (NaN if none); ``factors`` holds its h_alpha, h_beta,
            h_gamma, h_delta when the planner provides them.
        width_m: planned opening width of the executed grasp, metres.
        perception_s, planning_s, execution_s: wall-clock seconds of each phase.
        detail: a short human-readable reason (which IK failed, which contact was hit, ...).
        graspable: whether the oracle (:mod:`hsqbench.planner.oracle`, from the true meshes)
            found a feasible grasp in this presentation; None when not checked.
        object_pose: (x, y, z, qw, qx, qy, qz) of ``target`` (of the only object when there is
            no target) when the cloud was taken; empty when unknown.
        resting_pose: index of that object's resting pose in the scene (-1: upright).
        grasp_pose: (x, y, z, qw, qx, qy, qz) world pose of the TCP at the executed grasp (as
            executed: the planner's grasp, or its twin turned by pi about the approach axis,
            ``grasp_flipped``); for ``unreachable``, the planner's best grasp, which no motion
            reached; empty when no grasp was planned.
        grasp_flipped: the executed grasp is the planner's turned by pi about its approach axis.
        top_scores: scores of the planner's first grasps, best first (at most the trial config's
            ``recorded_scores``).
        motion_planning_s: wall-clock seconds of motion planning (IK), part of ``execution_s``.
        sim_time_s: simulated seconds of the executed motion (0 when nothing was executed).
        planner_stages_s: the planner's own wall-clock seconds per stage
            (``PlanResult.timings``; empty when it reports none).
        ranks_tried: distinct grasps motion-planned in this attempt.
    """

    outcome: Outcome
    target: str = ""
    rank_executed: int = -1
    n_grasps: int = 0
    score: float = float("nan")
    factors: dict[str, float] = field(default_factory=dict)
    width_m: float = float("nan")
    perception_s: float = 0.0
    planning_s: float = 0.0
    execution_s: float = 0.0
    detail: str = ""
    graspable: bool | None = None
    object_pose: tuple[float, ...] = ()
    resting_pose: int = -1
    grasp_pose: tuple[float, ...] = ()
    grasp_flipped: bool = False
    top_scores: tuple[float, ...] = ()
    motion_planning_s: float = 0.0
    sim_time_s: float = 0.0
    planner_stages_s: dict[str, float] = field(default_factory=dict)
    ranks_tried: int = 0

    @property
    def success(self) -> bool:
        return self.outcome == Outcome.SUCCESS

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["outcome"] = str(self.outcome)
        return out


@dataclass
class TrialResult:
    """An isolated-object trial: one object, one attempt (the paper's protocol).

    ``scene_settle_s``, ``scene_max_speed``: the scene's settling before the cameras looked
    (:class:`hsqbench.sim.scene.SceneInfo`'s ``settle_time_s`` and ``max_speed_after_settle``;
    NaN when not known), so a run shows which presentations were still moving.
    """

    object: str
    seed: int
    planner: str
    attempts: list[Attempt]
    scene_settle_s: float = float("nan")
    scene_max_speed: float = float("nan")

    @property
    def success(self) -> bool:
        return bool(self.attempts) and self.attempts[-1].success

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": "isolated",
            "object": self.object,
            "seed": self.seed,
            "planner": self.planner,
            "success": self.success,
            "scene_settle_s": self.scene_settle_s,
            "scene_max_speed": self.scene_max_speed,
            "attempts": [a.to_dict() for a in self.attempts],
        }


@dataclass
class RoundResult:
    """A packed round: attempts until the workspace is empty or two consecutive failures.

    ``objects_graspable``: the objects on which the oracle found a feasible grasp in the
    settled scene, before the first attempt (None when not checked).
    ``objects_lost``: those taken out of the round without being cleared (out of the workspace:
    fallen off the table, or pushed or dropped out of the cameras' view; or still on the hand
    once it is back home).
    ``scene_settle_s``, ``scene_max_speed``: as :class:`TrialResult`'s, for the round's scene.
    ``objects_unplaced``: objects of the round's draw that its scene generation did not put on
    the table (VGN/GIGA's packed scenes place what fits in 12 tries, and their generation takes
    out what falls outside the workspace): never presented, so not in ``objects``, the count
    that rates divide by. Empty for the harness's own scenes, which place every object.
    """

    objects: list[str]
    seed: int
    planner: str
    attempts: list[Attempt]
    objects_cleared: list[str]
    objects_graspable: list[str] | None = None
    objects_lost: list[str] = field(default_factory=list)
    scene_settle_s: float = float("nan")
    scene_max_speed: float = float("nan")
    objects_unplaced: list[str] = field(default_factory=list)

    @property
    def objects_presented(self) -> int:
        return len(self.objects)

    @property
    def clearance_rate(self) -> float:
        return len(self.objects_cleared) / max(1, len(self.objects))

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": "packed",
            "objects": list(self.objects),
            "seed": self.seed,
            "planner": self.planner,
            "objects_presented": self.objects_presented,
            "objects_cleared": list(self.objects_cleared),
            "objects_graspable": self.objects_graspable,
            "objects_lost": list(self.objects_lost),
            "objects_unplaced": list(self.objects_unplaced),
            "scene_settle_s": self.scene_settle_s,
            "scene_max_speed": self.scene_max_speed,
            "attempts": [a.to_dict() for a in self.attempts],
        }
