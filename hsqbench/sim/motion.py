"""Arm motion in the simulation: timed joint trajectories followed by the Panda's joint servos.

A :class:`JointTrajectory` runs through joint waypoints (K, 7) with one smooth time scaling: the
path parameter ``u`` in [0, K - 1] follows the minimum-jerk profile
``u(t) = (K - 1) (10 s^3 - 15 s^4 + 6 s^5)``, ``s = t / T``, which starts and ends at rest with
zero acceleration; between waypoints the path is a shape-preserving cubic (PCHIP) in joint
space, which never overshoots the waypoints, so a path checked at its waypoints and in between
does what was checked (two waypoints: a straight joint-space line). The duration ``T`` is the shortest that keeps every joint within
``speed_fraction`` of the Panda's rated joint speed and ``acceleration_fraction`` of its rated
acceleration (peak of the profile: ``du/dt = 1.875 (K - 1) / T``,
``d2u/dt2 = 5.77 (K - 1) / T^2``), and, for Cartesian lines, within the TCP speed and
acceleration limits.

Tracking: Menagerie's arm actuators are position servos ``tau = kp (u - q) - kv dq`` (plus the
joint damping ``b``). Commanding ``u = q_d + (kv + b) / kp * dq_d`` turns them into a PD tracker
of the reference ``(q_d, dq_d)`` (velocity feed-forward, as a real joint-impedance controller
does); without it the arm would trail the reference by ``(kv + b) / kp`` = 0.1 s.

:class:`Stepper` advances the simulation one step at a time, checks that it stays finite and
bounded (:class:`SimUnstable` otherwise; MuJoCo itself resets a state that turns NaN and only
raises a warning counter, which is checked too), and calls the recorder at a modest rate.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PchipInterpolator

from hsqbench.sim.recorder import NullRecorder, Recorder
from hsqbench.sim.robot import Panda

#: Time samples per waypoint segment when finding a trajectory's peak velocity and acceleration.
DURATION_SAMPLES_PER_SEGMENT = 200

#: MuJoCo warnings raised when it meets NaN/inf or huge values and resets the state.
_BAD_STATE_WARNINGS = (
    mujoco.mjtWarning.mjWARN_BADQPOS,
    mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC,
)

#: Peak velocity and acceleration of the minimum-jerk profile for a unit move in unit time.
MIN_JERK_PEAK_VELOCITY = 1.875
MIN_JERK_PEAK_ACCELERATION = 5.7735


@dataclass(frozen=True)
class MotionConfig:
    """Speeds and timings of the arm and hand (reasons in ``configs/trial.yaml``).

    Attributes:
        max_joint_velocity_rad_s: rated joint speeds of the Panda (7,), rad/s.
        max_joint_acceleration_rad_s2: rated joint accelerations (7,), rad/s^2.
        speed_fraction, acceleration_fraction: share of the rated limits used.
        min_move_time_s: shortest joint-space move.
        approach_speed_mps, approach_acceleration_mps2: TCP limits on the straight approach.
        lift_speed_mps, lift_acceleration_mps2: TCP limits on the lift and the lowering.
        settle_time_s: servo settling after a move, before the next phase.
        close_time_s: longest wait for the closing hand to come to rest on the object.
        open_time_s: longest wait for the opening hand to clear the object.
        fall_time_s: time for a released object to fall and come to rest.
        gripper_still_mps: the hand has come to rest when its width changes slower than this.
        max_speed: a speed above this (m/s) means a blown-up state: generalised velocities,
            with the angular ones of free bodies taken at the body's surface (times its
            bounding radius), so a small object spinning as the hand lets go is not one.
    """

    max_joint_velocity_rad_s: tuple[float, ...] = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
    max_joint_acceleration_rad_s2: tuple[float, ...] = (15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0)
    speed_fraction: float = 0.5
    acceleration_fraction: float = 0.3
    min_move_time_s: float = 0.3
    approach_speed_mps: float = 0.2
    approach_acceleration_mps2: float = 1.0
    lift_speed_mps: float = 0.3
    lift_acceleration_mps2: float = 1.5
    settle_time_s: float = 0.15
    close_time_s: float = 1.5
    open_time_s: float = 1.5
    fall_time_s: float = 0.5
    gripper_still_mps: float = 0.002
    max_speed: float = 50.0

    def __post_init__(self) -> None:
        if len(self.max_joint_velocity_rad_s) != 7 or len(self.max_joint_acceleration_rad_s2) != 7:
            raise ValueError("joint velocity and acceleration limits need 7 values each")
        for name in ("speed_fraction", "acceleration_fraction"):
            if not 0 < getattr(self, name) <= 1:
                raise ValueError(f"motion.{name} must be in (0, 1], got {getattr(self, name)}")
        for name in (
            "approach_speed_mps",
            "approach_acceleration_mps2",
            "lift_speed_mps",
            "lift_acceleration_mps2",
            "max_speed",
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f"motion.{name} must be positive, got {getattr(self, name)}")

    @property
    def joint_velocity_limit(self) -> NDArray[np.float64]:
        return self.speed_fraction * np.asarray(self.max_joint_velocity_rad_s)

    @property
    def joint_acceleration_limit(self) -> NDArray[np.float64]:
        return self.acceleration_fraction * np.asarray(self.max_joint_acceleration_rad_s2)


class SimUnstable(RuntimeError):
    """The simulation produced NaN, infinite or exploding values."""


def min_jerk(s: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Minimum-jerk profile: position and derivative (per unit s) at ``s`` in [0, 1] (clipped)."""
    s = np.clip(np.asarray(s, dtype=float), 0.0, 1.0)
    return s**3 * (10 - 15 * s + 6 * s * s), 30 * s * s * (1 - s) ** 2


class JointTrajectory:
    """Joint reference through ``waypoints`` (K, 7) in ``duration_s`` seconds (see module)."""

    def __init__(self, waypoints: ArrayLike, duration_s: float) -> None:
        w = np.asarray(waypoints, dtype=float)
        if w.ndim != 2 or w.shape[1] != 7 or len(w) < 2 or not np.all(np.isfinite(w)):
            raise ValueError(f"waypoints must be a finite (K >= 2, 7) array, got shape {w.shape}")
        if not duration_s > 0:
            raise ValueError(f"duration must be positive, got {duration_s}")
        self.waypoints = w
        self.duration_s = float(duration_s)
        self.segments = len(w) - 1
        self._spline = PchipInterpolator(np.arange(len(w)), w) if len(w) > 2 else None

    @property
    def end(self) -> NDArray[np.float64]:
        return self.waypoints[-1]

    def path(self, max_step_rad: float) -> NDArray[np.float64]:
        """Joint configurations (N, 7) along the path, at most ``max_step_rad`` apart in every
        joint (for checking the motion before running it)."""
        step = np.abs(np.diff(self.waypoints, axis=0)).max(axis=1)
        per = np.maximum(1, np.ceil(step / max_step_rad)).astype(int)
        u = np.concatenate([np.linspace(k, k + 1, n, endpoint=False) for k, n in enumerate(per)])
        u = np.append(u, self.segments)
        if self._spline is None:
            return self.waypoints[0] + (u / self.segments)[:, None] * (
                self.waypoints[1] - self.waypoints[0]
            )
        return self._spline(u)

    def sample(self, t: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Reference joint angles and velocities at time(s) ``t``: (7,) for a scalar, (n, 7) for
        n times (held at the ends)."""
        s, ds = min_jerk(np.asarray(t, dtype=float) / self.duration_s)
        u = s * self.segments
        du_dt = ds * self.segments / self.duration_s
        if self._spline is None:
            delta = self.waypoints[1] - self.waypoints[0]
            return self.waypoints[0] + s[..., None] * delta, du_dt[..., None] * delta
        return self._spline(u), self._spline(u, 1) * du_dt[..., None]


def joint_move_duration(waypoints: NDArray[np.float64], cfg: MotionConfig) -> float:
    """Shortest minimum-jerk duration through ``waypoints`` within the joint limits of ``cfg``.

    Velocities of a trajectory scale as ``1 / T`` and accelerations as ``1 / T^2``: the peaks
    ``v1``, ``a1`` of each joint over the trajectory with ``T = 1`` (sampled densely, with
    accelerations by finite differences) give ``T = max(v1 / v_max, sqrt(a1 / a_max))``."""
    w = np.asarray(waypoints, dtype=float)
    t = np.linspace(0.0, 1.0, DURATION_SAMPLES_PER_SEGMENT * (len(w) - 1) + 1)
    _, dq = JointTrajectory(w, 1.0).sample(t)
    ddq = np.gradient(dq, t, axis=0)
    t_v = np.abs(dq).max(axis=0) / cfg.joint_velocity_limit
    t_a = np.sqrt(np.abs(ddq).max(axis=0) / cfg.joint_acceleration_limit)
    return float(max(cfg.min_move_time_s, t_v.max(), t_a.max()))


def line_duration(length_m: float, speed_mps: float, accel_mps2: float) -> float:
    """Minimum-jerk duration of a straight TCP move of ``length_m`` within speed and acceleration."""
    return float(
        max(
            MIN_JERK_PEAK_VELOCITY * length_m / speed_mps,
            np.sqrt(MIN_JERK_PEAK_ACCELERATION * length_m / accel_mps2),
        )
    )


#: A check run during motion: returns a reason to stop, or None to go on.
Watch = Callable[[], "str | None"]


def surface_speed_scale(model: mujoco.MjModel) -> NDArray[np.float64]:
    """Per-dof factors turning generalised velocities into speeds (m/s): a free joint's
    angular dofs times its body's bounding radius about the body origin (the farthest geom
    extent), every other dof 1 (linear dofs are m/s; a hinge's rad/s is taken as it is)."""
    scale = np.ones(model.nv)
    extent = np.linalg.norm(model.geom_pos, axis=1) + model.geom_rbound
    radius = np.zeros(model.nbody)
    np.maximum.at(radius, model.geom_bodyid, extent)
    for j in np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE):
        adr = int(model.jnt_dofadr[j])
        scale[adr + 3 : adr + 6] = radius[model.jnt_bodyid[j]]
    return scale


class Stepper:
    """Steps one simulation and drives the Panda.

    Args:
        model, data: the simulation.
        panda: handles into ``model``.
        config: motion settings.
        recorder: called at ``recorder.step_interval_s`` (never when it is 0 or the recorder is
            disabled).
        check_every: run watches and the stability check every this many steps.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        panda: Panda,
        config: MotionConfig,
        recorder: Recorder | None = None,
        check_every: int = 5,
    ) -> None:
        self.model = model
        self.data = data
        self.panda = panda
        self.config = config
        self.recorder = recorder if recorder is not None else NullRecorder()
        self.dt = float(model.opt.timestep)
        self.check_every = max(1, int(check_every))
        rec_dt = getattr(self.recorder, "step_interval_s", 0.0) or 0.0
        self._record_every = (
            max(1, round(rec_dt / self.dt)) if self.recorder.enabled and rec_dt > 0 else 0
        )
        act = panda.arm_actuator_ids
        kp = model.actuator_gainprm[act, 0]
        kv = -model.actuator_biasprm[act, 2]
        self._feedforward = (kv + model.dof_damping[panda.arm_dof_adr]) / kp
        self._lo, self._hi = panda.arm_ctrl_range.T
        self.steps = 0
        self.phase = ""
        # A live view of MuJoCo's warning counters, read at every check.
        self._warnings = data.warning.number
        self._bad_warnings = np.array([int(k) for k in _BAD_STATE_WARNINGS])
        self._bad_state_seen = self._bad_state_count()
        self._speed_scale = surface_speed_scale(model)

    @property
    def time_s(self) -> float:
        return float(self.data.time)

    def _bad_state_count(self) -> int:
        return int(self._warnings[self._bad_warnings].sum())

    def _check_stable(self) -> None:
        d = self.data
        speed = np.abs(d.qvel) * self._speed_scale
        # The usual case in one test: finite (a sum with a NaN or inf is not) and slow enough.
        if (
            self._bad_state_count() <= self._bad_state_seen
            and np.isfinite(d.qpos.sum() + speed.sum())
            and (not speed.size or speed.max() <= self.config.max_speed)
        ):
            return
        if self._bad_state_count() > self._bad_state_seen:
            # MuJoCo found NaN/inf or a huge value and reset the state: the episode is void.
            raise SimUnstable(
                f"MuJoCo reset a diverged state (bad qpos, qvel or qacc) by t = {d.time:.3f} s "
                f"({self.phase})"
            )
        if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            raise SimUnstable(f"non-finite state at t = {d.time:.3f} s ({self.phase})")
        vmax = float(np.max(np.abs(d.qvel) * self._speed_scale)) if d.qvel.size else 0.0
        if vmax > self.config.max_speed:
            raise SimUnstable(
                f"a speed of {vmax:.0f} m/s (rad/s on a joint) at t = {d.time:.3f} s ({self.phase})"
            )

    def step(self, n: int = 1) -> None:
        """``n`` simulation steps with the current controls (the caller has set them)."""
        if self._record_every:
            for _ in range(n):
                mujoco.mj_step(self.model, self.data)
                self.steps += 1
                if self.steps % self._record_every == 0:
                    self.recorder.on_step(self.model, self.data, self.phase)
        else:
            mujoco.mj_step(self.model, self.data, n)  # the n steps in one call, in C
            self.steps += n

    def _run(
        self, n_steps: int, commands: NDArray[np.float64] | None, watches: tuple[Watch, ...]
    ) -> str | None:
        """Step ``n_steps`` times, the arm commanded ``commands[i]`` during step i (None: the
        controls as they are); stability and the watches checked every ``check_every`` steps
        and after the last."""
        ctrl, act, every = self.data.ctrl, self.panda.arm_actuator_ids, self.check_every
        for start in range(0, n_steps, every):
            stop = min(start + every, n_steps)
            if commands is None:
                self.step(stop - start)
            else:
                for i in range(start, stop):
                    ctrl[act] = commands[i]
                    self.step()
            self._check_stable()
            for watch in watches:
                reason = watch()
                if reason:
                    return reason
        return None

    def hold(self, duration_s: float, watches: tuple[Watch, ...] = ()) -> str | None:
        """Step for ``duration_s`` with the current controls; a watch's reason stops early."""
        return self._run(max(1, round(duration_s / self.dt)), None, watches)

    def close_hand(self) -> float:
        """Close with the grasp force and wait until the fingers come to rest (at least 0.2 s,
        at most ``close_time_s``); returns the width, metres."""
        self.panda.close_gripper(self.data)
        still = self.config.gripper_still_mps
        return self._wait_gripper(lambda w, v: v < still, 0.2, self.config.close_time_s)

    def open_hand(self, clear_width_m: float) -> float:
        """Open and wait until the width exceeds ``clear_width_m`` (at most ``open_time_s``);
        returns the width, metres."""
        self.panda.open_gripper(self.data)
        return self._wait_gripper(lambda w, v: w >= clear_width_m, 0.0, self.config.open_time_s)

    def _wait_gripper(
        self, done: Callable[[float, float], bool], min_s: float, max_s: float
    ) -> float:
        """Step in 50 ms windows until ``done(width, width speed)`` after ``min_s``, or ``max_s``."""
        window = max(1, round(0.05 / self.dt))
        t0 = self.data.time
        width = self.panda.gripper_width(self.data)
        while True:
            self.step(window)
            self._check_stable()
            new = self.panda.gripper_width(self.data)
            speed = abs(new - width) / (window * self.dt)
            width = new
            elapsed = self.data.time - t0
            if (elapsed >= min_s and done(width, speed)) or elapsed >= max_s:
                return width

    def follow(
        self, trajectory: JointTrajectory, watches: tuple[Watch, ...] = (), settle: bool = True
    ) -> str | None:
        """Track ``trajectory`` (then settle for ``settle_time_s``); a watch's reason stops it
        where it is (the arm is then told to hold its current position)."""
        act = self.panda.arm_actuator_ids
        ctrl = self.data.ctrl
        lo, hi = self._lo, self._hi
        n = max(1, round(trajectory.duration_s / self.dt))
        # The command applied during step i is the reference at the end of that step.
        q, dq = trajectory.sample(self.dt * np.arange(1, n + 1))
        commands = np.clip(q + self._feedforward * dq, lo, hi)
        reason = self._run(n, commands, watches)
        if reason is None:
            ctrl[act] = np.clip(trajectory.end, lo, hi)
            if settle:
                reason = self.hold(self.config.settle_time_s, watches)
        if reason is not None:
            ctrl[act] = np.clip(self.panda.arm_q(self.data), lo, hi)
        return reason

    def move_joints(
        self, q_target: ArrayLike, watches: tuple[Watch, ...] = (), settle: bool = True
    ) -> str | None:
        """Joint-space minimum-jerk move from the current angles to ``q_target``."""
        w = np.stack([self.panda.arm_q(self.data), np.asarray(q_target, dtype=float)])
        return self.follow(JointTrajectory(w, joint_move_duration(w, self.config)), watches, settle)
