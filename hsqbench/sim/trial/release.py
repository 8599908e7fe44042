"""The release of a held object over the bin: the hand turned toward pointing down, the
lowering on a checked line (shorter or shifted when the full one cannot be made), the open
hand's contacts and the withdrawal along the approach. The phase that uses them is
:func:`hsqbench.sim.trial.execution._release`."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.ik import Pose
from hsqbench.sim.motion import JointTrajectory, Watch, joint_move_duration, line_duration
from hsqbench.sim.sensor_noise import rotation_about
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.planning import sweep_problem


def line_trajectory(
    env: TrialEnv, waypoints: NDArray[np.float64], length_m: float, kind: str
) -> JointTrajectory:
    """Trajectory through a straight line's IK waypoints, timed by the TCP limits of ``kind``
    (``approach`` or ``lift``) and by the joint limits, whichever is slower."""
    m = env.config.motion
    speed, acc = (
        (m.approach_speed_mps, m.approach_acceleration_mps2)
        if kind == "approach"
        else (m.lift_speed_mps, m.lift_acceleration_mps2)
    )
    duration = max(line_duration(length_m, speed, acc), joint_move_duration(waypoints, m))
    return JointTrajectory(waypoints, duration)


def first_clear_line(
    env: TrialEnv, offsets: list[NDArray[np.float64]]
) -> tuple[NDArray[np.float64] | None, int, str]:
    """The first of the straight TCP lines from where the hand is, by ``offsets`` in turn, that
    can be solved and is clear of table and bin: ``(waypoints, index, problem)``, where
    ``problem`` is the first line's (empty when it can be made) and ``waypoints`` is None when
    none can."""
    d, panda = env.data, env.panda
    env.ik.sync(d)
    here = Pose(*panda.tcp_pose(d))
    first_problem = ""
    for k, offset in enumerate(offsets):
        path = env.ik.solve_line(
            here, here.position + offset, env.config.execution.lift_segments, panda.arm_q(d)
        )
        waypoints = np.vstack([panda.arm_q(d), path.q[1:]]) if path.ok else None
        problem = path.reason if waypoints is None else sweep_problem(env, *waypoints)
        if not problem:
            return waypoints, k, first_problem
        first_problem = first_problem or problem
    return None, -1, first_problem


def lowering(env: TrialEnv, drop: float) -> tuple[NDArray[np.float64] | None, float, float, str]:
    """The deepest lowering of the TCP by ``drop`` x ``execution.lowering_fractions`` that can be
    made, at each depth first straight down, then moved by ``execution.lowering_shifts_m``
    toward where the hand points (horizontally): a wrist turned sideways is then drawn away from
    the bin wall behind it. ``(waypoints, depth, shift, problem)`` as :func:`first_clear_line`."""
    ex = env.config.execution
    level, norm = _level(env.panda.tcp_pose(env.data)[1])
    shifts = (0.0, *ex.lowering_shifts_m) if norm > ex.shift_min_level else (0.0,)
    plan = [(f * drop, s) for f in ex.lowering_fractions for s in shifts]
    down = np.array([0.0, 0.0, -1.0])
    offsets = [depth * down + shift * level / max(norm, 1e-9) for depth, shift in plan]
    waypoints, k, problem = first_clear_line(env, offsets)
    depth, shift = plan[k] if waypoints is not None else (0.0, 0.0)
    return waypoints, depth, shift, problem


def _level(rotation: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """The horizontal part of a TCP frame's approach axis and its length: above
    ``execution.shift_min_level`` the hand is tilted enough for its wrist to stand beside it."""
    level = np.array([rotation[0, 2], rotation[1, 2], 0.0])
    return level, float(np.linalg.norm(level))


def rotation_toward_down(rotation: NDArray[np.float64], fraction: float) -> NDArray[np.float64]:
    """``rotation`` (a TCP frame, approach in column 2) turned by ``fraction`` of the smallest
    rotation that makes its approach point straight down (about the axis normal to both)."""
    a, down = rotation[:, 2], np.array([0.0, 0.0, -1.0])
    axis = np.cross(a, down)
    s, c = float(np.linalg.norm(axis)), float(a @ down)
    if s < 1e-9:
        return rotation.copy()
    return rotation_about(axis / s, fraction * float(np.arctan2(s, c))) @ rotation


def turn_down(env: TrialEnv, watches: tuple[Watch, ...]) -> str:
    """Turn a tilted hand, holding the object over the bin, about the TCP toward pointing
    straight down, by the first of ``execution.turn_down_fractions`` that the arm can make
    clear of table and bin: the wrist then stands above the hand, not beside it at the bin
    wall, so the lowering reaches the floor and the withdrawal rises against gravity (a cup
    wall on a tilted finger rides up with it; on a vertical one it slides off). The move is
    watched by ``watches``. Returns the detail's note: "" when the hand already points down or
    ``turn_down_fractions`` is empty."""
    d, panda = env.data, env.panda
    ex = env.config.execution
    position, rotation = panda.tcp_pose(d)
    if _level(rotation)[1] <= ex.shift_min_level or not ex.turn_down_fractions:
        return ""
    env.ik.sync(d)
    here = panda.arm_q(d)
    for f in ex.turn_down_fractions:
        target = Pose(position, rotation_toward_down(rotation, f))
        sol = env.ik.solve(target, here, env.rngs["ik"], restarts=ex.resolve_restarts)
        if not sol.ok or sweep_problem(env, here, sol.q):
            continue
        note = f" (turned {f:.0%} of the way to pointing down)"
        if reason := env.stepper.move_joints(sol.q, watches):
            note += f" (lost while turning: {reason})"
        return note
    return " (not turned: no turn toward pointing down reachable)"


@contextmanager
def open_hand_contacts(env: TrialEnv) -> Iterator[None]:
    """The solver's no-slip pass set to ``physics.open_hand_noslip_iterations`` while the open
    hand lets go of an object and backs out of it, and set back after: it exists to stop a
    squeezed grasp creeping, and on an open finger it would hold an object jammed there by
    interpenetrating hulls, by friction on forces the open hand does not exert."""
    opt = env.model.opt
    kept = opt.noslip_iterations
    opt.noslip_iterations = env.config.physics.open_hand_noslip_iterations
    try:
        yield
    finally:
        opt.noslip_iterations = kept


def withdraw(env: TrialEnv) -> str:
    """Pull the open hand back along its approach axis, as a place motion ends: an object still
    hooked on a finger (a cup's wall between the open pads after a release from higher up)
    slides off it; one that already fell is not touched. Tried shorter as the lowering is.
    Returns the detail's note."""
    back = -env.panda.tcp_pose(env.data)[1][:, 2] * env.config.execution.withdraw_m
    fractions = env.config.execution.lowering_fractions
    waypoints, k, problem = first_clear_line(env, [f * back for f in fractions])
    if waypoints is None:
        return f" (not withdrawn: {problem})"
    made = fractions[k] * env.config.execution.withdraw_m
    env.stepper.follow(line_trajectory(env, waypoints, made, "lift"), ())
    env.stepper.hold(env.config.motion.fall_time_s)
    return f" (withdrawn {made * 100:.0f} cm to free it from the fingers)"


def return_home(env: TrialEnv) -> None:
    """Open the hand, back out along the approach while an object still touches a finger (a
    cup or bag in the bin hooked on one would otherwise be lifted out with the hand), rise, and
    go home (between the attempts of a packed round), with :func:`open_hand_contacts`."""
    st, panda, d = env.stepper, env.panda, env.data
    st.phase = "home"
    with open_hand_contacts(env):
        st.open_hand(panda.max_width() - env.config.execution.release_gap_m)
        if env.probe.finger_contacts(d).any():
            withdraw(env)
        env.ik.sync(d)
        here = Pose(*panda.tcp_pose(d))
        up = env.ik.solve(
            here.moved([0.0, 0.0, env.config.execution.retreat_height_m]),
            panda.arm_q(d),
            restarts=env.config.execution.resolve_restarts,
        )
        if up.ok:
            st.move_joints(up.q, settle=False)
        st.move_joints(panda.home_arm_q)
