"""Execution of a planned grasp in the simulation, as a list of phases (:data:`PHASES`), each
returning an outcome (the attempt ends there) or None (the next phase runs), judged on the way
by the rules of :mod:`hsqbench.sim.judge`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hsqbench.sim.ik import Pose
from hsqbench.sim.judge import HoldWatch, approach_watch, judge_closed
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.geometry import carry_pose
from hsqbench.sim.trial.planning import GraspMotion, sweep_problem
from hsqbench.sim.trial.release import (
    line_trajectory,
    lowering,
    open_hand_contacts,
    turn_down,
    withdraw,
)


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
        reason = st.follow(line_trajectory(env, motion.descent, drop, "lift"), (x.watch,))
    if reason:
        return Outcome.COLLISION_ON_APPROACH, x.intended, f"moving to the pre-grasp: {reason}"
    return None


def _approach(x: _Execution) -> Verdict:
    length = x.env.config.execution.pregrasp_distance_m
    traj = line_trajectory(x.env, x.motion.approach, length, "approach")
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
    traj = line_trajectory(x.env, x.motion.lift, x.motion.lift_height_m, "lift")
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


def _release(x: _Execution) -> Verdict:
    """Turn a tilted hand toward pointing down, lower the object toward the bin floor on a
    checked line, open, and judge where it came to rest (the steps: :mod:`release
    <hsqbench.sim.trial.release>`). A lowering that cannot be solved or would sweep the arm into
    the bin is tried moved away from the wrist, then shorter; when none can be run the hand opens
    where it is, over the bin. An object that slips or leaves a finger during the lowering is
    released there. An object not in the bin once the hand is open, or still touching a finger,
    may hang on one: the hand is withdrawn along its approach before it is judged; from the
    opening on, the contacts are those of ``open_hand_contacts``. The release succeeds when the
    object lies in the bin free of the fingers; one still on them (wedged between the open pads)
    would leave with the hand. A higher release is not a failure; the detail says so."""
    env, d, probe = x.env, x.env.data, x.env.probe
    cfg = env.config
    note = x.note + turn_down(env, (x.hold,))
    drop = probe.lowest_z(d, x.target) - (env.bin_box.lo[2] + cfg.execution.release_height_m)
    if drop > cfg.execution.min_lowering_m:
        waypoints, depth, shift, problem = lowering(env, drop)
        if problem and depth < drop:
            note += f" (released {(drop - depth) * 100:.0f} cm higher: lowering {problem})"
        if shift:
            why = "" if depth < drop else f": straight down, {problem}"
            note += f" (lowered {shift * 100:.0f} cm off the bin centre, away from the wrist{why})"
        if waypoints is not None:
            traj = line_trajectory(env, waypoints, float(np.hypot(depth, shift)), "lift")
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


def execute_grasp(
    env: TrialEnv, motion: GraspMotion, intended: str, until: str = "release"
) -> ExecutionResult:
    """Run one planned grasp in the simulation and judge it, phase by phase (:data:`PHASES`;
    the rules: :mod:`hsqbench.sim.trial` and :mod:`hsqbench.sim.judge`). ``until``: the last
    phase run; an object still held after it is a success (``"lift"``: VGN/GIGA's test, held
    after the lift, with the object still in the hand)."""
    names = [n for n, _ in PHASES]
    if until not in names:
        raise ValueError(f"until must be one of the phases {names}, got {until!r}")
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
        if name == until:
            detail = f"held after the {name}{x.note}"
            return ExecutionResult(
                Outcome.SUCCESS, x.target, detail, float(d.time - t_start), phases
            )
    raise AssertionError("the release phase always returns an outcome")
