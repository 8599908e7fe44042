"""Motion planning of one grasp: IK for every phase (hover, descent, approach, lift, carry),
checked against the table, the bin and the perceived cloud (:class:`GraspMotion`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.ik import Pose
from hsqbench.sim.motion import JointTrajectory, joint_move_duration
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.geometry import carry_pose, first_pose

#: Name of the joint-space move to the first pose in reasons.
MOVE_IN = "move to the first pose"


@dataclass
class GraspMotion:
    """Joint-space plan of one grasp (angles in radians).

    Attributes:
        grasp_pose: TCP target at the grasp (possibly the flipped twin of the planner's).
        q_first: (7,) end of the joint-space move: the hover pose, or the pre-grasp without one.
        descent: (K, 7) waypoints of the vertical line from the hover pose down to the
            pre-grasp, or None.
        approach: (K, 7) waypoints from the pre-grasp to the grasp.
        lift: (K, 7) waypoints of the lift.
        lift_height_m: TCP rise of the lift.
        q_carry: (7,) estimated configuration above the bin.
        carry_yaw_rad: turn about the world z axis from the lifted pose to the carry pose.
        flipped: the grasp was turned by pi about its approach axis.
    """

    grasp_pose: Pose
    q_first: NDArray[np.float64]
    descent: NDArray[np.float64] | None
    approach: NDArray[np.float64]
    lift: NDArray[np.float64]
    lift_height_m: float
    q_carry: NDArray[np.float64]
    carry_yaw_rad: float
    flipped: bool


def _carry_seed(q_lift: NDArray[np.float64], yaw: float, env: TrialEnv) -> NDArray[np.float64]:
    q = q_lift.copy()
    q[0] = np.clip(q[0] + yaw, env.ik.lower[0], env.ik.upper[0])
    return q


def plan_grasp_motion(
    env: TrialEnv, pose: Pose, flipped: bool, clear_z: float, q_grasp: NDArray[np.float64]
) -> tuple[GraspMotion | None, str]:
    """IK for every phase of one grasp pose, given its solution ``q_grasp``; ``(None, reason)``
    when a phase is unreachable.

    The chain is solved from the grasp outward (the grasp pose is the hardest: nearest the table
    and the object), each line seeded by the previous solution so the arm stays on one branch:
    the approach line back to the pre-grasp, the vertical line up to the hover pose (when the
    pre-grasp is lower than ``clear_z``, see :func:`~hsqbench.sim.trial.geometry.first_pose`), the lift, and the carry.
    """
    ik, ex = env.ik, env.config.execution
    first, pre = first_pose(pose, ex.pregrasp_distance_m, env.hand_box, clear_z)
    back = ik.solve_line(pose, pre.position, ex.approach_segments, q_grasp)
    if not back.ok:
        return None, f"approach {back.reason}"
    approach = back.q[::-1].copy()
    descent = None
    if first is not pre:
        rise = float(first.position[2] - pre.position[2])
        n = max(1, int(np.ceil(rise / ex.waypoint_spacing_m)))
        up = ik.solve_line(pre, first.position, n, approach[0])
        if not up.ok:
            return None, f"descent from the hover pose {up.reason}"
        descent = up.q[::-1].copy()
    q_first = approach[0] if descent is None else descent[0]
    height = env.lift_height()
    lift = ik.solve_line(
        pose, pose.position + np.array([0.0, 0.0, height]), ex.lift_segments, q_grasp
    )
    if not lift.ok:
        return None, f"lift {lift.reason}"
    lifted = pose.moved([0.0, 0.0, height])
    carry, yaw = carry_pose(env.bin_centre_xy(), lifted, pose.position[:2])
    seed = _carry_seed(lift.q[-1], yaw, env)
    carry_sol = ik.solve(carry, seed, env.rngs["ik"], closest_to=seed)
    if not carry_sol.ok:
        return None, f"carry {carry_sol.reason}"
    return (
        GraspMotion(pose, q_first, descent, approach, lift.q, height, carry_sol.q, yaw, flipped),
        "",
    )


def plan_motion(
    env: TrialEnv, grasp: Any, clear_z: float, cloud: NDArray[np.float64]
) -> tuple[GraspMotion | None, str]:
    """Plan a planner grasp and its twin turned by pi about the approach axis (the same
    parallel-jaw grasp); of the two, the one whose first pose the arm reaches with the shorter
    joint-space move.

    The grasp pose is solved with restarts; its solutions (branches), nearest the arm's current
    angles first, are tried for the whole chain (:func:`plan_grasp_motion`), which must then
    keep clear of the table and bin everywhere and of the cloud on the way in
    (:func:`_motion_problem`). A joint-space move that would swing through the objects (it is
    a straight line in joint space, not in space) is retried with the hover pose raised by
    ``hover_raise_m``, so the hand turns over the objects and comes down on a vertical line.
    """
    ik, panda, rng = env.ik, env.panda, env.rngs["ik"]
    ik.sync(env.data, panda.max_width())
    q_now = panda.arm_q(env.data)
    pose = Pose(grasp.position, grasp.rotation)
    best: tuple[float, GraspMotion] | None = None
    reasons = []
    heights = (clear_z, clear_z + env.config.execution.hover_raise_m)
    for p, flipped in ((pose, False), (pose.flipped(), True)):
        label = "flipped" if flipped else "as planned"
        at_grasp = ik.solve(p, q_now, rng, closest_to=q_now)
        if not at_grasp.ok and at_grasp.position_error_m <= env.config.ik.position_tolerance_m:
            # Reached, but the fingers touch the table: the planner's gripper model and the
            # hand's meshes differ by a few millimetres; raise the grasp that little.
            deficit = -ik.hand_margin(at_grasp.q)
            if 0 < deficit <= env.config.execution.table_nudge_max_m:
                p = p.moved([0.0, 0.0, deficit + env.config.execution.nudge_extra_m])
                at_grasp = ik.solve(p, q_now, rng, closest_to=q_now)
        if not at_grasp.ok:
            reasons.append(f"{label}: grasp pose {at_grasp.reason}")
            continue
        motion, reason = None, ""
        for q_grasp in [at_grasp.q, *at_grasp.alternatives][: env.config.ik.grasp_branches]:
            for z in heights:
                motion, reason = plan_grasp_motion(env, p, flipped, z, q_grasp)
                if motion is not None:
                    reason = _motion_problem(env, motion, q_now, cloud)
                    motion = None if reason else motion
                if motion is not None or not reason.startswith(MOVE_IN):
                    break
            if motion is not None:
                break
        if motion is None:
            reasons.append(f"{label}: {reason}")
            continue
        cost = joint_move_duration(np.stack([q_now, motion.q_first]), env.config.motion)
        if best is None or cost < best[0]:
            best = (cost, motion)
    if best is None:
        return None, "; ".join(reasons)
    return best[1], ""


def _motion_problem(
    env: TrialEnv, motion: GraspMotion, q_now: NDArray[np.float64], cloud: NDArray[np.float64]
) -> str:
    """Why a planned grasp motion is unsafe (``""`` if it is not): a robot part too near the
    table or bin anywhere along it, or the arm passing through the cloud on the way in."""
    checks = [
        (MOVE_IN, (q_now, motion.q_first)),
        ("descent", () if motion.descent is None else tuple(motion.descent)),
        ("approach", tuple(motion.approach)),
        ("lift", tuple(motion.lift)),
        ("carry", (motion.lift[-1], motion.q_carry)),
    ]
    for name, waypoints in checks:
        if len(waypoints) > 1 and (problem := sweep_problem(env, *waypoints)):
            return f"{name}: {problem}"
    return _cloud_problem(env, cloud, (q_now, motion.q_first), motion.descent)


def sweep_problem(env: TrialEnv, *waypoints: NDArray[np.float64]) -> str:
    """Why the motion through joint ``waypoints`` (two: a joint-space move; more: a line's IK
    waypoints) is unsafe, a robot part coming closer to the table or bin than it may anywhere
    along the path the trajectory follows; ``""`` when it is safe."""
    w = np.vstack(waypoints)
    path = JointTrajectory(w, 1.0).path(env.config.ik.sweep_step_rad)
    margin, g, d, k = env.ik.sweep_clearance(path)
    if margin >= 0:
        return ""
    body = env.model.body(env.model.geom_bodyid[g]).name
    return f"{body} would come {d * 1000:.1f} mm from the table or bin at {k / max(1, len(path) - 1):.0%} of it"


def _cloud_problem(
    env: TrialEnv, cloud: NDArray[np.float64], *motions: Sequence[NDArray[np.float64]] | None
) -> str:
    """Why a move toward the grasp would run the arm into the perceived objects (the cloud),
    or ``""``: checked for the joint-space move to the first pose and the descent, which must
    pass clear of everything (the approach itself enters between the objects' surfaces, as the
    planner checked)."""
    names = (MOVE_IN, "descent")
    for name, waypoints in zip(names, motions, strict=False):
        if waypoints is None or len(waypoints) < 2:
            continue
        path = JointTrajectory(np.vstack(waypoints), 1.0).path(env.config.ik.sweep_step_rad)
        ex = env.config.execution
        k, g, n = env.ik.points_hit(path, cloud, ex.cloud_clearance_m, ex.cloud_min_points)
        if k >= 0:
            body = env.model.body(env.model.geom_bodyid[g]).name
            where = k / max(1, len(path) - 1)
            return f"{name}: {body} would pass through {n} cloud points at {where:.0%} of it"
    return ""
