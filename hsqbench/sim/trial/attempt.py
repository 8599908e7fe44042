"""One attempt: perceive, plan, motion-plan and execute a grasp (the data flows
observation -> :class:`~hsqbench.planner.api.PlanResult` -> :class:`MotionPlan` ->
:class:`~hsqbench.sim.trial.execution.ExecutionResult` -> :class:`~hsqbench.sim.outcome.Attempt`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.failure import PlannerError, checked_plan
from hsqbench.sim.motion import SimUnstable
from hsqbench.sim.outcome import Attempt, Outcome
from hsqbench.sim.recorded_pose import pose7
from hsqbench.sim.trial.config import TrialConfig
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.execution import ExecutionResult, execute_grasp
from hsqbench.sim.trial.ordering import distinct_in_order
from hsqbench.sim.trial.planning import GraspMotion, plan_motion


@dataclass
class AttemptTrace:
    """Timings and facts of one attempt beyond :class:`Attempt` (for benchmarks and debugging).

    Attributes:
        n_points: perceived cloud size.
        ik_s: wall seconds of motion planning (IK), part of ``execution_s``.
        sim_s: wall seconds of simulation, part of ``execution_s``.
        sim_time_s: simulated seconds of the execution.
        phases: simulated seconds per motion phase.
        ranks_tried: distinct grasps motion-planned (duplicates of failed ones are skipped).
        flipped: the executed grasp was the twin turned by pi.
        scene_build_s: wall seconds of building the scene (first attempt of a trial or round; a
            presentation kept from an earlier planner: resetting it;
            0 for later attempts). The first ``perception_s`` includes making the sensor.
        graspable_objects: objects on the table with a feasible oracle grasp at this attempt
            (None: not checked).
    """

    n_points: int = 0
    ik_s: float = 0.0
    sim_s: float = 0.0
    sim_time_s: float = 0.0
    phases: dict[str, float] = field(default_factory=dict)
    ranks_tried: int = 0
    flipped: bool = False
    scene_build_s: float = 0.0
    graspable_objects: list[str] | None = None


@dataclass
class MotionPlan:
    """The grasp chosen for execution: its rank in the planner's list and its motion (None and
    -1 when no grasp tried is executable, ``reasons`` then says why, one per rank)."""

    rank: int
    motion: GraspMotion | None
    reasons: list[str]


def resolve_planner(planner: Any, config: TrialConfig) -> Any:
    """A planner object from a name (``hsqbench.planner.registry.get_planner``) or the object itself."""
    if isinstance(planner, str):
        from hsqbench.planner.registry import get_planner

        return get_planner(planner, config.planners.for_planner(planner))
    if not hasattr(planner, "plan"):
        raise TypeError(
            f"planner must be a name or have a plan(points, context) method: {planner!r}"
        )
    return planner


def _finish(env: TrialEnv, attempt: Attempt, trace: AttemptTrace) -> tuple[Attempt, AttemptTrace]:
    if env.recorder.enabled:
        env.recorder.on_outcome(attempt)
    return attempt, trace


def _presented(env: TrialEnv, trace: AttemptTrace, graspable: list[str] | None) -> dict[str, Any]:
    """What the attempt records about the presentation: graspable, and for a single object its
    pose and resting pose."""
    trace.graspable_objects = graspable
    presented: dict[str, Any] = {"graspable": None if graspable is None else bool(graspable)}
    if len(env.info.objects) == 1:
        only = env.info.objects[0]
        presented["object_pose"] = env.object_pose(only)
        presented["resting_pose"] = env.info.resting_poses.get(only, -1)
    return presented


def _plan(env: TrialEnv, planner: Any, points: Any, obs: Any, truth: Any, packed: bool) -> Any:
    from hsqbench.planner.api import PlanningContext

    context = PlanningContext(
        support_plane=tuple(float(x) for x in env.info.support_plane),
        packed=packed,
        seed=int(env.rngs["planner"].integers(2**31)),
        camera_positions=np.asarray(obs.camera_positions),
        workspace_bounds=(np.asarray(env.info.workspace_min), np.asarray(env.info.workspace_max)),
        truth=truth if getattr(planner, "privileged", False) else None,
        scene=env.info.kind,
        depth_views=getattr(obs, "cameras", None),
    )
    return checked_plan(planner, points, context)


def plan_motions(env: TrialEnv, grasps: Any, points: Any, trace: AttemptTrace) -> MotionPlan:
    """Motion-plan the grasps in execution order (:mod:`hsqbench.sim.trial.ordering`) until
    one is executable, at most ``max_ranks`` distinct ones."""
    ex = env.config.execution
    # The hover height clears what the robot sees; a privileged planner may plan with an empty
    # cloud (objects outside the cameras' crop), and then only the table is in the way.
    top = float(points[:, 2].max()) if len(points) else env.info.table_top_z
    clear_z = top + ex.hover_clearance_m
    cloud = voxel_downsample(points, ex.cloud_voxel_m).points
    reasons: list[str] = []
    for r in distinct_in_order(grasps, env.config.max_ranks, env.config.ordering):
        motion, reason = plan_motion(env, grasps[r], clear_z, cloud)
        trace.ranks_tried += 1
        if motion is not None:
            return MotionPlan(r, motion, reasons)
        reasons.append(f"rank {r}: {reason}")
    return MotionPlan(-1, None, reasons)


def plan_fields(
    plan: Any, perception_s: float, planning_s: float, recorded_scores: int
) -> dict[str, Any]:
    """What every attempt records of its look and plan (the trial's and the clutter round's)."""
    n_top = min(len(plan.grasps), recorded_scores)
    return {
        "n_grasps": len(plan.grasps),
        "perception_s": perception_s,
        "planning_s": planning_s,
        "top_scores": tuple(float(plan.grasps[i].score) for i in range(n_top)),
        "planner_stages_s": {k: float(v) for k, v in plan.timings.items()},
    }


def grasp_fields(grasp: Any, rank: int) -> dict[str, Any]:
    """What an attempt records of the grasp it executed, the ``rank``-th of the planner's."""
    return {
        "rank_executed": rank,
        "score": float(grasp.score),
        "factors": {k: float(v) for k, v in grasp.factors.items()},
        "width_m": float(grasp.width),
    }


def _pose_of(env: TrialEnv, presented: dict[str, Any], name: str) -> dict[str, Any]:
    # The target's pose as perceived (nothing has moved yet); isolated scenes have it already.
    if "object_pose" in presented or not name:
        return {}
    return {
        "object_pose": env.object_pose(name),
        "resting_pose": env.info.resting_poses.get(name, -1),
    }


def run_attempt(env: TrialEnv, planner: Any, packed: bool) -> tuple[Attempt, AttemptTrace]:
    """Perceive, plan, motion-plan and execute one grasp (:mod:`hsqbench.sim.trial`)."""
    cfg, rec = env.config, env.recorder
    trace = AttemptTrace()
    try:
        look = env.look()
    except SimUnstable as exc:
        return Attempt(Outcome.SIM_UNSTABLE, detail=str(exc)), trace
    obs, perception_s, truth = look.obs, look.perception_s, look.truth
    points = np.asarray(obs.points)
    trace.n_points = len(points)
    if rec.enabled:
        rec.on_observation(obs)
    presented = _presented(env, trace, look.graspable)
    if len(points) < cfg.min_cloud_points and not getattr(planner, "privileged", False):
        detail = f"the cloud has {len(points)} points (fewer than {cfg.min_cloud_points})"
        attempt = Attempt(
            Outcome.NO_GRASP_FOUND, perception_s=perception_s, detail=detail, **presented
        )
        return _finish(env, attempt, trace)

    t0 = time.perf_counter()
    try:
        plan = _plan(env, planner, points, obs, truth, packed)
    except PlannerError as exc:  # the planner's own failure: a failed attempt of that planner
        attempt = Attempt(
            Outcome.PLANNER_ERROR,
            perception_s=perception_s,
            planning_s=time.perf_counter() - t0,
            detail=str(exc),
            **presented,
        )
        return _finish(env, attempt, trace)
    planning_s = time.perf_counter() - t0
    if rec.enabled:
        rec.on_plan(plan)
    common = {**plan_fields(plan, perception_s, planning_s, cfg.recorded_scores), **presented}
    if not len(plan.grasps):
        detail = plan.reason or "the planner returned no grasp"
        return _finish(env, Attempt(Outcome.NO_GRASP_FOUND, detail=detail, **common), trace)
    return _execute(env, plan.grasps, points, presented, common, trace)


def _execute(
    env: TrialEnv,
    grasps: Any,
    points: Any,
    presented: dict[str, Any],
    common: dict[str, Any],
    trace: AttemptTrace,
) -> tuple[Attempt, AttemptTrace]:
    """Motion-plan the grasps, execute the first executable one, and record the attempt."""
    d = env.data
    t0 = time.perf_counter()
    chosen = plan_motions(env, grasps, points, trace)
    trace.ik_s = time.perf_counter() - t0
    if chosen.motion is None:
        top, reasons = grasps[0], chosen.reasons
        intended = env.probe.nearest_object(d, np.asarray(top.position))
        attempt = Attempt(
            Outcome.UNREACHABLE,
            target=intended,
            score=float(top.score),
            factors=dict(top.factors),
            width_m=float(top.width),
            execution_s=trace.ik_s,
            grasp_pose=pose7(top.position, top.rotation),
            motion_planning_s=trace.ik_s,
            ranks_tried=trace.ranks_tried,
            detail=reasons[0] if len(reasons) == 1 else f"{len(reasons)} grasps: {reasons[0]}",
            **common,
            **_pose_of(env, presented, intended),
        )
        return _finish(env, attempt, trace)

    grasp, motion = grasps[chosen.rank], chosen.motion
    trace.flipped = motion.flipped
    if env.recorder.enabled:
        env.recorder.on_grasp(grasp, chosen.rank)
    intended = env.probe.nearest_object(d, np.asarray(grasp.position))
    common.update(_pose_of(env, presented, intended))
    t1 = time.perf_counter()
    try:
        res = execute_grasp(env, motion, intended)
    except SimUnstable as exc:
        res = ExecutionResult(Outcome.SIM_UNSTABLE, intended, str(exc))
    trace.sim_s = time.perf_counter() - t1
    trace.sim_time_s, trace.phases = res.sim_time_s, res.phases
    attempt = Attempt(
        res.outcome,
        target=res.target,
        **grasp_fields(grasp, chosen.rank),
        execution_s=time.perf_counter() - t0,
        grasp_pose=pose7(motion.grasp_pose.position, motion.grasp_pose.rotation),
        grasp_flipped=motion.flipped,
        motion_planning_s=trace.ik_s,
        sim_time_s=res.sim_time_s,
        ranks_tried=trace.ranks_tried,
        detail=res.detail,
        **common,
    )
    return _finish(env, attempt, trace)
