"""Execution of a planned grasp in the simulation, as a list of phases (:data:`PHASES`), each
returning an outcome (the attempt ends there) or None (the next phase runs), judged on the way
by the rules of :mod:`hsqbench.sim.judge`."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.ik import Pose
from hsqbench.sim.judge import HoldWatch, approach_watch, judge_closed
from hsqbench.sim.motion import JointTrajectory, joint_move_duration, line_duration
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.geometry import carry_pose
from hsqbench.sim.trial.planning import GraspMotion, sweep_problem


@dataclass
class ExecutionResult:
    """What execution found: outcome, the object it concerned, details and phase times."""

    outcome: Outcome
    target: str
    detail: str
    sim_time_s: float = 0.0
    phases: dict[str, float] = field(default_factory=dict)


@dataclass
class _Execution:
    """The state the phases share: the plan, the object meant and, once closed, the one held."""

    env: TrialEnv
    motion: GraspMotion
    intended: str
    watch: Callable[[], str | None]
    target: str = ""
    hold: HoldWatch | None = None
    held_width_m: float = 0.0
    note: str = ""  # what the detail adds about how the object was carried


#: A phase's verdict: (outcome, target, detail), or None to go on.
Verdict = tuple[Outcome, str, str] | None


def _line_trajectory(
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


def _pregrasp(x: _Execution) -> Verdict:
    """Joint-space move to the hover pose (then the vertical descent) or the pre-grasp."""
    env, motion, st = x.env, x.motion, x.env.stepper
    reason = st.move_joints(motion.q_first, (x.watch,), settle=motion.descent is None)
    if reason is None and motion.descent is not None:
        drop = float(
            np.linalg.norm(
                env.ik.forward(motion.descent[0]).position
                - env.ik.forward(motion.descent[-1]).position
            )
        )
        reason = st.follow(_line_trajectory(env, motion.descent, drop, "lift"), (x.watch,))
    if reason:
        return Outcome.COLLISION_ON_APPROACH, x.intended, f"moving to the pre-grasp: {reason}"
    return None


def _approach(x: _Execution) -> Verdict:
    length = x.env.config.execution.pregrasp_distance_m
    traj = _line_trajectory(x.env, x.motion.approach, length, "approach")
    reason = x.env.stepper.follow(traj, (x.watch,))
    if reason:
        return Outcome.COLLISION_ON_APPROACH, x.intended, f"approaching: {reason}"
    return None


def _close(x: _Execution) -> Verdict:
    env, d = x.env, x.env.data
    width = env.stepper.close_hand()
    held = env.probe.held_objects(d) if width >= env.config.judge.empty_width_m else []
    empty = judge_closed(width, held, env.config.judge)
    if empty:
        return Outcome.EMPTY_GRASP, x.intended, empty
    tcp = env.panda.tcp_pose(d)[0]
    x.target = min(held, key=lambda n: float(np.linalg.norm(env.probe.position(d, n) - tcp)))
    x.hold = HoldWatch(env.probe, d, x.target, env.config.judge)
    x.held_width_m = width
    return None


def _lift(x: _Execution) -> Verdict:
    traj = _line_trajectory(x.env, x.motion.lift, x.motion.lift_height_m, "lift")
    reason = x.env.stepper.follow(traj, (x.hold,))
    if reason:
        assert x.hold is not None
        outcome, detail = x.hold.loss(reason, "lift")
        return outcome, x.target, detail
    return None


def _carry(x: _Execution) -> Verdict:
    """Centre the held object over the bin (its actual position in the hand): the carry pose
    re-solved for it and checked like every planned motion (:func:`sweep_problem`). When that
    cannot be solved or would sweep the arm into the table or bin, the planned carry (which puts
    the grasp point over the bin centre: the object a few cm off it, still over the floor) is
    run if it passes the same check from where the arm is, and the detail says so; else the
    carry is ``unreachable``."""
    env, d, panda = x.env, x.env.data, x.env.panda
    env.ik.sync(d)
    lifted = Pose(*panda.tcp_pose(d))
    carry, _ = carry_pose(env.bin_centre_xy(), lifted, env.probe.position(d, x.target)[:2])
    restarts = env.config.execution.resolve_restarts
    sol = env.ik.solve(carry, x.motion.q_carry, env.rngs["ik"], restarts=restarts)
    q, here = sol.q, panda.arm_q(d)
    problem = sol.reason if not sol.ok else sweep_problem(env, here, sol.q)
    if problem:
        if sweep_problem(env, here, x.motion.q_carry):
            return Outcome.UNREACHABLE, x.target, f"carry over the bin: {problem}"
        q, x.note = x.motion.q_carry, f" (carried as planned: re-solved carry {problem})"
    reason = env.stepper.move_joints(q, (x.hold,))
    if reason:
        return Outcome.DROPPED, x.target, f"during the carry: {reason}{x.note}"
    return None


def _first_clear_line(
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


def _lowering(env: TrialEnv, drop: float) -> tuple[NDArray[np.float64] | None, float, float, str]:
    """The deepest lowering of the TCP by ``drop`` x ``execution.lowering_fractions`` that can be
    made, at each depth first straight down, then moved by ``execution.lowering_shifts_m``
    toward where the hand points (horizontally): a wrist turned sideways is then drawn away from
    the bin wall behind it. ``(waypoints, depth, shift, problem)`` as :func:`_first_clear_line`."""
    ex = env.config.execution
    approach = env.panda.tcp_pose(env.data)[1][:, 2]
    level = np.array([approach[0], approach[1], 0.0])
    norm = float(np.linalg.norm(level))
    shifts = (0.0, *ex.lowering_shifts_m) if norm > ex.shift_min_level else (0.0,)
    plan = [(f * drop, s) for f in ex.lowering_fractions for s in shifts]
    down = np.array([0.0, 0.0, -1.0])
    offsets = [depth * down + shift * level / max(norm, 1e-9) for depth, shift in plan]
    waypoints, k, problem = _first_clear_line(env, offsets)
    depth, shift = plan[k] if waypoints is not None else (0.0, 0.0)
    return waypoints, depth, shift, problem


def rotation_toward_down(rotation: NDArray[np.float64], fraction: float) -> NDArray[np.float64]:
    """``rotation`` (a TCP frame, approach in column 2) turned by ``fraction`` of the smallest
    rotation that makes its approach point straight down (about the axis normal to both)."""
    a, down = rotation[:, 2], np.array([0.0, 0.0, -1.0])
    axis = np.cross(a, down)
    s, c = float(np.linalg.norm(axis)), float(a @ down)
    if s < 1e-9:
        return rotation.copy()
    k = axis / s
    angle = fraction * float(np.arctan2(s, c))
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    turn = np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)
    return turn @ rotation


def _turn_down(x: _Execution) -> str:
    """Turn a tilted hand, holding the object over the bin, about the TCP toward pointing
    straight down, by the first of ``execution.turn_down_fractions`` that the arm can make
    clear of table and bin: the wrist then stands above the hand, not beside it at the bin
    wall, so the lowering reaches the floor and the withdrawal rises against gravity (a cup
    wall on a tilted finger rides up with it; on a vertical one it slides off). Returns the
    detail's note ("" when the hand already points down or no turn could be made)."""
    env, d, panda = x.env, x.env.data, x.env.panda
    ex = env.config.execution
    position, rotation = panda.tcp_pose(d)
    if float(np.hypot(*rotation[:2, 2])) <= ex.shift_min_level or not ex.turn_down_fractions:
        return ""
    env.ik.sync(d)
    here = panda.arm_q(d)
    for f in ex.turn_down_fractions:
        target = Pose(position, rotation_toward_down(rotation, f))
        sol = env.ik.solve(target, here, env.rngs["ik"], restarts=ex.resolve_restarts)
        if not sol.ok or sweep_problem(env, here, sol.q):
            continue
        note = f" (turned {f:.0%} of the way to pointing down)"
        if reason := env.stepper.move_joints(sol.q, (x.hold,)):
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
    waypoints, k, problem = _first_clear_line(env, [f * back for f in fractions])
    if waypoints is None:
        return f" (not withdrawn: {problem})"
    made = fractions[k] * env.config.execution.withdraw_m
    env.stepper.follow(_line_trajectory(env, waypoints, made, "lift"), ())
    env.stepper.hold(env.config.motion.fall_time_s)
    return f" (withdrawn {made * 100:.0f} cm to free it from the fingers)"


def _release(x: _Execution) -> Verdict:
    """Lower the object toward the bin floor on a checked line, open, and judge where it came to
    rest. A lowering that cannot be solved or would sweep the arm into the bin is tried moved
    away from the wrist, then shorter (:func:`_lowering`); when none can be run the hand opens
    where it is, over the bin. An object that slips or leaves a finger during the lowering is
    released there. An object not in the bin once the hand is open, or still touching a finger,
    may hang on one: the hand is withdrawn along its approach (:func:`withdraw`) before it is
    judged; from the opening on, the contacts are those of :func:`open_hand_contacts`. The
    release succeeds when the object lies in the bin free of the fingers; one still on them
    (wedged between the open pads) would leave with the hand. A higher release is not a
    failure; the detail says so."""
    env, d, probe = x.env, x.env.data, x.env.probe
    cfg = env.config
    note = x.note + _turn_down(x)
    drop = probe.lowest_z(d, x.target) - (env.bin_box.lo[2] + cfg.execution.release_height_m)
    if drop > cfg.execution.min_lowering_m:
        waypoints, depth, shift, problem = _lowering(env, drop)
        if problem and depth < drop:
            note += f" (released {(drop - depth) * 100:.0f} cm higher: lowering {problem})"
        if shift:
            why = "" if depth < drop else f": straight down, {problem}"
            note += f" (lowered {shift * 100:.0f} cm off the bin centre, away from the wrist{why})"
        if waypoints is not None:
            traj = _line_trajectory(env, waypoints, float(np.hypot(depth, shift)), "lift")
            # Lost here, the object is already over the bin, lower than the carry: the hand
            # stops and opens as for a release, and where the object comes to rest decides.
            if reason := env.stepper.follow(traj, (x.hold,)):
                note += f" (lost while lowering: {reason})"
    with open_hand_contacts(env):
        env.stepper.open_hand(x.held_width_m + cfg.execution.release_gap_m)
        env.stepper.hold(cfg.motion.fall_time_s)
        if not probe.in_bin(d, x.target) or probe.on_hand(d, x.target):
            note += withdraw(env)
    where = probe.position(d, x.target).round(3).tolist()
    if not probe.in_bin(d, x.target):
        return Outcome.DROPPED, x.target, f"released but not in the bin (at {where} m){note}"
    if probe.on_hand(d, x.target):
        # Wedged between the open pads or hooked on one: the hand would carry it away.
        return Outcome.DROPPED, x.target, f"still on the open hand after the release{note}"
    return Outcome.SUCCESS, x.target, "in the bin" + note


#: The phases in order, by the names the stepper, the recorder and the phase times use.
PHASES: tuple[tuple[str, Callable[[_Execution], Verdict]], ...] = (
    ("pregrasp", _pregrasp),
    ("approach", _approach),
    ("close", _close),
    ("lift", _lift),
    ("carry", _carry),
    ("release", _release),
)


def execute_grasp(env: TrialEnv, motion: GraspMotion, intended: str) -> ExecutionResult:
    """Run one planned grasp in the simulation and judge it, phase by phase (:data:`PHASES`;
    the rules: :mod:`hsqbench.sim.trial` and :mod:`hsqbench.sim.judge`)."""
    d = env.data
    t_start = d.time
    phases: dict[str, float] = {}
    env.panda.open_gripper(d)
    start = env.probe.positions(d)
    x = _Execution(env, motion, intended, approach_watch(env.probe, d, start, env.config.judge))
    for name, phase in PHASES:
        t0 = d.time
        env.stepper.phase = name
        verdict = phase(x)
        phases[name] = float(d.time - t0)
        if verdict is not None:
            outcome, target, detail = verdict
            return ExecutionResult(outcome, target, detail, float(d.time - t_start), phases)
    raise AssertionError("the release phase always returns an outcome")
