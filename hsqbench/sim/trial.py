"""The trial runner: perceive, plan, and execute grasps with the Panda in a MuJoCo scene.

One attempt (:func:`run_attempt`):

1. **Perceive** the fused cloud (the two depth cameras of :mod:`hsqbench.sim.perception`, or the
   fast :mod:`hsqbench.sim.surface_sensor` stand-in), with the arm at home, out of view.
2. **Plan** with the planner (``PlanningContext``: table plane, ``packed``, seed, cameras,
   workspace). No grasp: ``no_grasp_found``.
3. **Motion plan** (IK, :mod:`hsqbench.sim.ik`) the grasps in score order, equal scores (the
   rolls of one closing line) with the most easily reached approach first, up to ``max_ranks``
   distinct grasps. For each grasp and its twin turned by pi about the approach axis (the same
   parallel-jaw grasp): solve the grasp pose (restarts; branches nearest the current posture
   first), then outward from it the straight approach line back to the pre-grasp
   (``pregrasp_distance_m`` along the approach axis), the vertical line up to a hover pose when
   the pre-grasp is low (so the joint-space move ends above the objects), the vertical lift and
   the carry pose above the bin. The motion must keep the arm off the table and bin all along
   and, on the way in, out of the perceived cloud. Of the twins the one with the shorter
   joint-space move is executed. None executable: ``unreachable``.
4. **Execute** (:mod:`hsqbench.sim.motion`): joint-space move to the hover pose or pre-grasp;
   vertical descent; straight approach; close with the 70 N hand; lift; carry (mostly a turn of
   the base joint) above the bin; lower; open. Judged on the way (:mod:`hsqbench.sim.judge`):

   - ``collision_on_approach``: before the fingers close, the robot presses the table or bin
     (``table_contact_force_n``), or pushes an object (``object_contact_force_n``) farther than
     ``pushed_distance_m``. The motion stops there.
   - ``empty_grasp``: after closing, the fingers are closed (``empty_width_m``) or no object
     touches both fingers; or the object is lost during the lift before it rose
     ``lifted_height_m``.
   - ``dropped``: the object was lifted, then left a finger for ``lost_time_s`` or slipped
     ``slip_distance_m`` in the hand (at the point held between the pads) before the release;
     or it was released but did not come to rest inside the bin.
   - ``success``: held from the lift to the release, and at rest inside the bin afterwards (the
     paper: "grasps the object and moves it from the workspace to a bin next to the arm without
     dropping it").
   - ``sim_unstable``: NaN or exploding state at any point (never a success).

Isolated trial (:func:`run_isolated_trial`): one object at a seeded random upright pose, one
attempt. Packed round (:func:`run_packed_round`): the paper's rule, attempts until no object is
left on the table or two consecutive failures; after each attempt the hand opens, the arm goes
home, and objects in the bin (cleared) or off the table (not cleared) are taken out of the scene.

Determinism: everything random comes from ``seed`` (scene layout, sensor noise and calibration,
planner seed, IK restarts, each from its own ``SeedSequence`` stream) and MuJoCo is deterministic,
so the same seed and config give the same outcomes and numbers (timings aside).

Where the runner uses simulator truth rather than what the robot perceives: the judge (as any
simulated benchmark) and the names in the records (``target``: the object held, or nearest the
grasp); and, after the lift, the held object's position and lowest point, used to centre it over
the bin and lower it before release (a real robot would use a conservative fixed height). The
lift height is not: objects start on the table, so the lift that brings their bottom over the
bin walls follows from the table and bin alone.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.sim.ik import ArmIK, IKConfig, Pose
from hsqbench.sim.judge import Box, JudgeConfig, SceneProbe
from hsqbench.sim.motion import (
    JointTrajectory,
    MotionConfig,
    SimUnstable,
    Stepper,
    joint_move_duration,
    line_duration,
)
from hsqbench.sim.objects import ObjectLike, resolve_object
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult, TrialResult
from hsqbench.sim.recorder import NullRecorder, Recorder
from hsqbench.sim.robot import Panda
from hsqbench.sim.surface_sensor import SurfaceSensor, SurfaceSensorConfig

#: Where removed objects are parked (metres; far outside the table, cameras and arm).
PARK_X_M, PARK_Y_M = 10.0, 10.0

#: Added to a table nudge so the raised grasp clears the required distance, metres.
NUDGE_EXTRA_M = 0.0005

#: Name of the joint-space move to the first pose in reasons.
MOVE_IN = "move to the first pose"

#: Grasps looked at per rank tried when ordering ties (see :func:`_execution_order`).
TIE_WINDOW = 8
#: Weight of "away from the robot" against "down" in the easy approach direction.
EASY_APPROACH_OUTWARD = 0.4

#: Independent random streams drawn from a trial's seed.
_STREAMS = ("perception_calibration", "perception_noise", "ik", "planner", "oracle")


@dataclass(frozen=True)
class ExecutionConfig:
    """Geometry of the grasp execution, metres (reasons in ``configs/trial.yaml``).

    Attributes:
        pregrasp_distance_m: pre-grasp pose distance back along the approach axis.
        approach_segments: IK waypoints on the approach line (segments).
        lift_height_m: smallest lift of the TCP.
        lift_segments: IK waypoints on the lift line (segments).
        hover_clearance_m: gap between the hand's lowest point and the cloud's top at the hover
            pose (straight above a pre-grasp that is lower than that).
        waypoint_spacing_m: IK waypoint spacing on the descent from the hover pose.
        table_nudge_max_m: a grasp whose fingers would come closer to the table than the IK
            clearance by at most this much is raised by the deficit.
        hover_raise_m: how much higher the hover pose goes when the joint-space move to the
            lower one would swing the arm through the objects.
        cloud_voxel_m: the cloud is thinned to this voxel size for the arm's collision checks.
        cloud_clearance_m: the arm's bounding boxes, grown by this, must hold fewer than
            ``cloud_min_points`` cloud points on the way to the pre-grasp.
        cloud_min_points: that many points in a box are an obstacle (fewer: sensor outliers).
        carry_clearance_m: height of the object's bottom above the bin walls while carried.
        release_height_m: height of the object's bottom above the bin floor at release.
        retreat_height_m: TCP rise before returning home after an attempt (packed rounds).
        release_gap_m: the hand has let go when it is this much wider than when it held.
    """

    pregrasp_distance_m: float = 0.1
    approach_segments: int = 4
    lift_height_m: float = 0.1
    lift_segments: int = 4
    hover_clearance_m: float = 0.03
    waypoint_spacing_m: float = 0.05
    table_nudge_max_m: float = 0.005
    hover_raise_m: float = 0.15
    cloud_voxel_m: float = 0.01
    cloud_clearance_m: float = 0.01
    cloud_min_points: int = 3
    carry_clearance_m: float = 0.04
    release_height_m: float = 0.03
    retreat_height_m: float = 0.1
    release_gap_m: float = 0.01

    def __post_init__(self) -> None:
        if self.approach_segments < 1 or self.lift_segments < 1:
            raise ValueError("execution: approach_segments and lift_segments must be >= 1")
        for name in ("pregrasp_distance_m", "lift_height_m", "carry_clearance_m"):
            if getattr(self, name) <= 0:
                raise ValueError(f"execution.{name} must be positive, got {getattr(self, name)}")


@dataclass(frozen=True)
class PackedConfig:
    """Packed-round rule: stop after ``max_consecutive_failures`` failures in a row (the
    paper: two) or ``max_attempts`` attempts (a cap that the rule reaches first in practice)."""

    max_consecutive_failures: int = 2
    max_attempts: int = 15

    def __post_init__(self) -> None:
        if self.max_consecutive_failures < 1 or self.max_attempts < 1:
            raise ValueError("packed: max_consecutive_failures and max_attempts must be >= 1")


@dataclass(frozen=True)
class PileRoundConfig:
    """Pile rounds: the packed rule (``packed:``), plus whether a round also ends at the first
    attempt where the planner finds no grasp (VGN/GIGA's rule; off: it counts as a failure, as
    in packed rounds)."""

    stop_on_no_grasp: bool = False


@dataclass(frozen=True)
class TrialConfig:
    """``configs/trial.yaml``: how one trial runs (see the comments there for each reason).

    Attributes:
        scene, robot, physics: config names (in ``configs/``) of the scene parts.
        sensor: ``cameras`` (rendered depth, :mod:`hsqbench.sim.perception`) or ``surface``
            (the fast stand-in, :mod:`hsqbench.sim.surface_sensor`).
        perception: config name of the cameras' perception (``sensor: cameras``).
        surface: settings of the stand-in (``sensor: surface``).
        planner_config: config handed to ``get_planner`` (None: the planner's default).
        graspability: oracle config (``configs/oracle.yaml``) with which every attempt checks
            whether the presentation is graspable at all (``Attempt.graspable``); None: no check.
        max_ranks: grasps tried in score order before an attempt is ``unreachable``.
        min_cloud_points: fewer perceived points than this: nothing to grasp.
        execution, ik, motion, judge, packed, pile: see their classes.
        overrides: dotted paths into the trial's config tree -> values (a sweep point's
            settings; :mod:`hsqbench.overrides`): the parts' paths apply when a part is loaded,
            the own fields' are already applied.
    """

    scene: str = "scene"
    robot: str = "robot"
    physics: str = "physics"
    sensor: Literal["cameras", "surface"] = "cameras"
    perception: str = "perception"
    surface: SurfaceSensorConfig = field(default_factory=SurfaceSensorConfig)
    planner_config: str | None = None
    graspability: str | None = "oracle"
    max_ranks: int = 48
    min_cloud_points: int = 30
    execution: ExecutionConfig = field(default_factory=ExecutionConfig)
    ik: IKConfig = field(default_factory=IKConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    judge: JudgeConfig = field(default_factory=JudgeConfig)
    packed: PackedConfig = field(default_factory=PackedConfig)
    pile: PileRoundConfig = field(default_factory=PileRoundConfig)
    overrides: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.max_ranks < 1:
            raise ValueError(f"max_ranks must be >= 1, got {self.max_ranks}")


def load_trial_config(path: str | Path | None = "trial") -> TrialConfig:
    """Load ``configs/trial.yaml`` (or another file, its ``overrides:`` applied); ``None`` gives
    the built-in defaults."""
    from hsqbench.overrides import load_trial_tree

    return TrialConfig() if path is None else load_trial_tree(TrialConfig, path, {})


# ---- environment -------------------------------------------------------------------------------


def _rot_z(angle: float) -> NDArray[np.float64]:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


class TrialEnv:
    """A built scene with everything an attempt needs (robot handles, IK, probe, sensor).

    Build with :meth:`build`; close with :meth:`close` (frees the cameras' renderers).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        info: Any,
        assets: dict[str, ObjectLike],
        config: TrialConfig,
        seed: int,
        recorder: Recorder,
    ) -> None:
        self.model, self.data, self.info = model, data, info
        self.assets = assets
        self.config = config
        self.seed = seed
        self.recorder = recorder
        streams = np.random.SeedSequence(seed).spawn(len(_STREAMS))
        self.rngs = {n: np.random.default_rng(s) for n, s in zip(_STREAMS, streams, strict=True)}
        self.panda = Panda(model, info.robot_prefix)
        obstacles = np.array([info.table_geom_id, *info.bin_geom_ids], dtype=int)
        self.ik = ArmIK(model, self.panda, config.ik, obstacles)
        self.ik.sync(data, self.panda.max_width())
        #: (lo, hi) bounding box of the open hand in the TCP frame, metres.
        self.hand_box = self.ik.hand_extent()
        self.bin_box = Box(np.asarray(info.bin_min, float), np.asarray(info.bin_max, float))
        table_half = np.asarray(model.geom_size[info.table_geom_id, :2])
        table_c = np.asarray(model.geom_pos[info.table_geom_id, :2])
        self.table_box = Box(
            np.array([*(table_c - table_half), info.table_top_z - config.judge.off_table_below_m]),
            np.array([*(table_c + table_half), info.table_top_z + 2.0]),
        )
        self.probe = SceneProbe(
            model, self.panda, info.object_body_ids, obstacles, self.bin_box, self.table_box
        )
        self.stepper = Stepper(model, data, self.panda, config.motion, recorder)
        self.removed: set[str] = set()
        self._sensor: Any = None
        self._oracle: Any = None

    @classmethod
    def build(
        cls,
        kind: str,
        objects: Sequence[str | ObjectLike] | str | ObjectLike | None,
        seed: int,
        config: TrialConfig,
        recorder: Recorder | None = None,
    ) -> TrialEnv:
        from hsqbench.overrides import load_part
        from hsqbench.sim.scene import build_scene

        if isinstance(objects, str) or (objects is not None and not isinstance(objects, Sequence)):
            objects = [objects]
        resolved = None if objects is None else [resolve_object(o) for o in objects]
        model, data, info = build_scene(
            kind,
            resolved,
            seed,
            scene_config=load_part(config.scene, "scene", config.overrides),
            robot_config=load_part(config.robot, "robot", config.overrides),
            physics_config=load_part(config.physics, "physics", config.overrides),
        )
        if resolved is None:
            resolved = [resolve_object(n) for n in info.objects]
        assets = {a.name: a for a in resolved}
        rec = recorder if recorder is not None else NullRecorder()
        env = cls(model, data, info, assets, config, seed, rec)
        if rec.enabled:
            rec.on_scene(model, data, info)
        return env

    def close(self) -> None:
        if self._sensor is not None and hasattr(self._sensor, "close"):
            self._sensor.close()
        self._sensor = None

    def __enter__(self) -> TrialEnv:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- sensing -------------------------------------------------------------------------------
    def _make_sensor(self) -> Any:
        cfg = self.config
        if cfg.sensor == "surface":
            return SurfaceSensor(
                self.assets,
                self.info.object_body_ids,
                [self.model.camera(c.name).id for c in self.info.depth_cameras],
                self.info.workspace_min,
                self.info.workspace_max,
                self.info.table_top_z,
                cfg.surface,
            )
        from hsqbench.overrides import load_part
        from hsqbench.sim.perception import Perception

        return Perception.from_scene(
            self.model,
            self.info,
            rng=self.rngs["perception_calibration"],
            config=load_part(cfg.perception, "perception", cfg.overrides),
        )

    def observe(self) -> Any:
        """The perceived cloud now (``points`` (N, 3), ``camera_positions`` (C, 3))."""
        if self._sensor is None:
            self._sensor = self._make_sensor()
        if isinstance(self._sensor, SurfaceSensor):
            self._sensor.objects = {n: a for n, a in self.assets.items() if n not in self.removed}
        mujoco.mj_forward(self.model, self.data)
        return self._sensor.observe(self.data, self.rngs["perception_noise"])

    # ---- truth (the oracle's; never a perceiving planner's) ------------------------------------
    def truth(self) -> Any:
        """The true hulls of the objects on the table now (:mod:`hsqbench.sim.scene_truth`)."""
        from hsqbench.sim.scene_truth import scene_truth

        names = self.objects_on_table()
        seed = int(self.rngs["oracle"].integers(2**31))
        return scene_truth(
            self.model, self.data, self.info.object_geom_ids, names, self.info.support_plane, seed
        )

    def graspable_objects(self, truth: Any) -> list[str] | None:
        """Objects on which the oracle finds a feasible grasp (None: the check is off)."""
        if self.config.graspability is None:
            return None
        from hsqbench.planner.oracle import OraclePlanner, feasible_grasps

        if self._oracle is None:
            self._oracle = OraclePlanner(self.config.graspability)
        counts = feasible_grasps(truth, self._oracle.gripper, self._oracle.config, truth.seed)
        return [n for n, c in counts.items() if c > 0]

    def object_pose(self, name: str) -> tuple[float, ...]:
        """(x, y, z, qw, qx, qy, qz) of an object now."""
        body = self.info.object_body_ids[name]
        adr = self.model.jnt_qposadr[self.model.body_jntadr[body]]
        return tuple(float(x) for x in self.data.qpos[adr : adr + 7])

    # ---- scene bookkeeping ---------------------------------------------------------------------
    def objects_on_table(self) -> list[str]:
        """Objects not removed, resting on the table (not in the bin, not fallen off)."""
        return [
            n
            for n in self.info.objects
            if n not in self.removed
            and self.probe.on_table(self.data, n)
            and not self.probe.in_bin(self.data, n)
        ]

    def remove(self, name: str) -> None:
        """Take an object out of the scene: parked far away, floating (gravity compensated),
        with its collisions off, so it never touches anything again."""
        k = self.info.objects.index(name)
        body = self.info.object_body_ids[name]
        self.model.body_gravcomp[body] = 1.0
        geoms = self.model.geom_bodyid == body
        self.model.geom_contype[geoms] = 0
        self.model.geom_conaffinity[geoms] = 0
        self.probe.set_free_pose(self.data, name, np.array([PARK_X_M + k, PARK_Y_M, 1.0]))
        self.removed.add(name)
        mujoco.mj_forward(self.model, self.data)


# ---- motion planning ---------------------------------------------------------------------------


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


def _lift_height(env: TrialEnv) -> float:
    """TCP rise that brings an object standing on the table above the bin walls plus the
    clearance (objects start on the table: their lowest point is the table top)."""
    ex = env.config.execution
    need = env.bin_box.hi[2] + ex.carry_clearance_m - env.info.table_top_z
    return float(max(ex.lift_height_m, need))


def _carry_pose(env: TrialEnv, lifted: Pose, held_xy: NDArray[np.float64]) -> tuple[Pose, float]:
    """Carry target: the lifted TCP pose turned about the world z axis so that the held point
    ``held_xy`` (object centre, or the grasp point before execution) lands over the bin centre,
    at the same height and with the same tilt."""
    bin_c = 0.5 * (env.bin_box.lo[:2] + env.bin_box.hi[:2])
    yaw = float(np.arctan2(bin_c[1], bin_c[0]) - np.arctan2(held_xy[1], held_xy[0]))
    yaw = float((yaw + np.pi) % (2 * np.pi) - np.pi)
    rz = _rot_z(yaw)
    offset = rz[:2, :2] @ (lifted.position[:2] - held_xy)
    position = np.array([*(bin_c + offset), lifted.position[2]])
    return Pose(position, rz @ lifted.rotation), yaw


def _carry_seed(q_lift: NDArray[np.float64], yaw: float, env: TrialEnv) -> NDArray[np.float64]:
    q = q_lift.copy()
    q[0] = np.clip(q[0] + yaw, env.ik.lower[0], env.ik.upper[0])
    return q


def _first_pose(env: TrialEnv, pose: Pose, clear_z: float) -> tuple[Pose, Pose]:
    """(first, pre): the end of the joint-space move and the pre-grasp pose. ``first`` is the
    hover pose straight above the pre-grasp where the hand's lowest point is at ``clear_z``
    (when the pre-grasp is lower than that), else the pre-grasp itself."""
    pre = pose.moved(-env.config.execution.pregrasp_distance_m * pose.rotation[:, 2])
    lo, hi = env.hand_box
    row = pose.rotation[2]
    below = float(row @ (0.5 * (lo + hi)) - np.abs(row) @ (0.5 * (hi - lo)))
    descent = clear_z - below - pre.position[2]
    return (pre.moved([0.0, 0.0, descent]) if descent > 0 else pre), pre


def plan_grasp_motion(
    env: TrialEnv, pose: Pose, flipped: bool, clear_z: float, q_grasp: NDArray[np.float64]
) -> tuple[GraspMotion | None, str]:
    """IK for every phase of one grasp pose, given its solution ``q_grasp``; ``(None, reason)``
    when a phase is unreachable.

    The chain is solved from the grasp outward (the grasp pose is the hardest: nearest the table
    and the object), each line seeded by the previous solution so the arm stays on one branch:
    the approach line back to the pre-grasp, the vertical line up to the hover pose (when the
    pre-grasp is lower than ``clear_z``, see :func:`_first_pose`), the lift, and the carry.
    """
    ik, ex = env.ik, env.config.execution
    first, pre = _first_pose(env, pose, clear_z)
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
    height = _lift_height(env)
    lift = ik.solve_line(
        pose, pose.position + np.array([0.0, 0.0, height]), ex.lift_segments, q_grasp
    )
    if not lift.ok:
        return None, f"lift {lift.reason}"
    lifted = pose.moved([0.0, 0.0, height])
    carry, yaw = _carry_pose(env, lifted, pose.position[:2])
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
                p = p.moved([0.0, 0.0, deficit + NUDGE_EXTRA_M])
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
        if len(waypoints) > 1 and (problem := _sweep_problem(env, *waypoints)):
            return f"{name}: {problem}"
    return _cloud_problem(env, cloud, (q_now, motion.q_first), motion.descent)


def _sweep_problem(env: TrialEnv, *waypoints: NDArray[np.float64]) -> str:
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


def _execution_order(grasps: Sequence[Any], window: int) -> list[int]:
    """Ranks of the first ``window`` grasps in the order they are tried: by score, best first;
    among equal scores (the rolls of one closing line score the same, and the planner leaves
    their order arbitrary) the approach nearest "down and away from the robot" first, the
    direction the arm reaches most easily."""
    n = min(window, len(grasps))
    keys = []
    for r in range(n):
        g = grasps[r]
        p, a = np.asarray(g.position), np.asarray(g.rotation)[:, 2]
        radial = np.array([p[0], p[1], 0.0]) / max(float(np.hypot(p[0], p[1])), 1e-9)
        easy = radial * EASY_APPROACH_OUTWARD + np.array([0.0, 0.0, -1.0])
        keys.append((-round(float(g.score), 9), -float(a @ easy), r))
    return [k[2] for k in sorted(keys)]


def _grasp_key(grasp: Any) -> tuple:
    """The same physical grasp gives the same key: P_G to 1 mm, approach axis to ~0.6 deg, and
    the closing axis up to its sign."""
    closing = np.asarray(grasp.rotation)[:, 0]
    closing = closing if (closing[np.argmax(np.abs(closing))] > 0) else -closing
    return (
        tuple(np.round(np.asarray(grasp.position) / 0.001).astype(int)),
        tuple(np.round(np.asarray(grasp.rotation)[:, 2] / 0.01).astype(int)),
        tuple(np.round(closing / 0.01).astype(int)),
    )


# ---- execution ---------------------------------------------------------------------------------


@dataclass
class ExecutionResult:
    """What execution found: outcome, the object it concerned, details and phase times."""

    outcome: Outcome
    target: str
    detail: str
    sim_time_s: float = 0.0
    phases: dict[str, float] = field(default_factory=dict)


class _Hold:
    """Watches that an object stays in the hand: touching both fingers, and the point of it
    that was between the pads when the hand closed still there (it may pivot about it)."""

    def __init__(self, env: TrialEnv, name: str) -> None:
        self.env, self.name = env, name
        self.k = env.probe.names.index(name)
        self.point = env.probe.tcp_in_object(env.data, name)
        self.z0 = float(env.probe.position(env.data, name)[2])
        self.max_rise = 0.0
        self.out_since: float | None = None

    def __call__(self) -> str | None:
        env, d, j = self.env, self.env.data, self.env.config.judge
        self.max_rise = max(self.max_rise, float(env.probe.position(d, self.name)[2]) - self.z0)
        touching = env.probe.finger_contacts(d)[self.k]
        if touching.all():
            self.out_since = None
        elif self.out_since is None:
            self.out_since = float(d.time)
        if self.out_since is not None and d.time - self.out_since >= j.lost_time_s:
            side = "left" if not touching[0] else "right"
            return f"{self.name} left the {side} finger"
        slip = env.probe.slip(d, self.name, self.point)
        if slip > j.slip_distance_m:
            return f"{self.name} slipped {slip * 100:.1f} cm in the hand"
        return None


def _approach_watch(env: TrialEnv, start: NDArray[np.float64]):
    j = env.config.judge
    names = env.probe.names

    def watch() -> str | None:
        table_f, obj_f, body = env.probe.robot_forces(env.data)
        if table_f > j.table_contact_force_n:
            return f"{body} hit the table or bin ({table_f:.0f} N)"
        moved = np.linalg.norm(env.probe.positions(env.data) - start, axis=1)
        pushed = (obj_f > j.object_contact_force_n) & (moved > j.pushed_distance_m)
        if pushed.any():
            k = int(np.argmax(np.where(pushed, moved, -1.0)))
            return f"hand pushed {names[k]} {moved[k] * 100:.1f} cm ({obj_f[k]:.0f} N)"
        return None

    return watch


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


def execute_grasp(env: TrialEnv, motion: GraspMotion, intended: str) -> ExecutionResult:
    """Run one planned grasp in the simulation and judge it (module docstring)."""
    st, panda, probe, d = env.stepper, env.panda, env.probe, env.data
    cfg, j = env.config, env.config.judge
    t_start = d.time
    phases: dict[str, float] = {}

    def mark(name: str, t0: float) -> None:
        phases[name] = float(d.time - t0)

    def result(outcome: Outcome, target: str, detail: str) -> ExecutionResult:
        return ExecutionResult(outcome, target, detail, float(d.time - t_start), phases)

    panda.open_gripper(d)
    start = probe.positions(d)
    watch = _approach_watch(env, start)

    t0 = d.time
    st.phase = "pregrasp"
    reason = st.move_joints(motion.q_first, (watch,), settle=motion.descent is None)
    if reason is None and motion.descent is not None:
        drop = float(
            np.linalg.norm(
                env.ik.forward(motion.descent[0]).position
                - env.ik.forward(motion.descent[-1]).position
            )
        )
        reason = st.follow(_line_trajectory(env, motion.descent, drop, "lift"), (watch,))
    mark("pregrasp", t0)
    if reason:
        return result(Outcome.COLLISION_ON_APPROACH, intended, f"moving to the pre-grasp: {reason}")

    t0 = d.time
    st.phase = "approach"
    length = cfg.execution.pregrasp_distance_m
    reason = st.follow(_line_trajectory(env, motion.approach, length, "approach"), (watch,))
    mark("approach", t0)
    if reason:
        return result(Outcome.COLLISION_ON_APPROACH, intended, f"approaching: {reason}")

    t0 = d.time
    st.phase = "close"
    width = st.close_hand()
    mark("close", t0)
    if width < j.empty_width_m:
        return result(
            Outcome.EMPTY_GRASP, intended, f"fingers closed fully ({width * 1000:.1f} mm)"
        )
    held = probe.held_objects(d)
    if not held:
        return result(
            Outcome.EMPTY_GRASP, intended, f"no object between the fingers ({width * 1000:.0f} mm)"
        )
    tcp = panda.tcp_pose(d)[0]
    target = min(held, key=lambda n: float(np.linalg.norm(probe.position(d, n) - tcp)))
    hold = _Hold(env, target)
    held_width = width

    t0 = d.time
    st.phase = "lift"
    traj = _line_trajectory(env, motion.lift, motion.lift_height_m, "lift")
    reason = st.follow(traj, (hold,))
    mark("lift", t0)
    if reason:
        if hold.max_rise > j.lifted_height_m:
            return result(Outcome.DROPPED, target, f"during the lift: {reason}")
        return result(Outcome.EMPTY_GRASP, target, f"not lifted: {reason}")

    # Carry: centre the held object over the bin (its actual position in the hand).
    t0 = d.time
    st.phase = "carry"
    env.ik.sync(d)
    lifted = Pose(*panda.tcp_pose(d))
    carry, _ = _carry_pose(env, lifted, probe.position(d, target)[:2])
    sol = env.ik.solve(carry, motion.q_carry, env.rngs["ik"], restarts=1)
    q_carry = sol.q if sol.ok else motion.q_carry
    reason = st.move_joints(q_carry, (hold,))
    mark("carry", t0)
    if reason:
        return result(Outcome.DROPPED, target, f"during the carry: {reason}")

    # Lower the object toward the bin floor, then open.
    t0 = d.time
    st.phase = "release"
    drop = probe.lowest_z(d, target) - (env.bin_box.lo[2] + cfg.execution.release_height_m)
    if drop > 0.01:
        env.ik.sync(d)
        here = Pose(*panda.tcp_pose(d))
        path = env.ik.solve_line(
            here,
            here.position - np.array([0.0, 0.0, drop]),
            cfg.execution.lift_segments,
            panda.arm_q(d),
        )
        if path.ok:
            waypoints = np.vstack([panda.arm_q(d), path.q[1:]])
            reason = st.follow(_line_trajectory(env, waypoints, drop, "lift"), (hold,))
            if reason:
                mark("release", t0)
                return result(Outcome.DROPPED, target, f"lowering into the bin: {reason}")
    st.open_hand(held_width + cfg.execution.release_gap_m)
    st.hold(cfg.motion.fall_time_s)
    mark("release", t0)
    if probe.in_bin(d, target):
        return result(Outcome.SUCCESS, target, "in the bin")
    where = probe.position(d, target).round(3).tolist()
    return result(Outcome.DROPPED, target, f"released but not in the bin (at {where} m)")


# ---- attempts, trials, rounds ------------------------------------------------------------------


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
        scene_build_s: wall seconds of building the scene (first attempt of a trial or round;
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


def resolve_planner(planner: Any, config: TrialConfig) -> Any:
    """A planner object from a name (``hsqbench.planner.get_planner``) or the object itself."""
    if isinstance(planner, str):
        from hsqbench.planner import get_planner

        return get_planner(planner, config.planner_config)
    if not hasattr(planner, "plan"):
        raise TypeError(
            f"planner must be a name or have a plan(points, context) method: {planner!r}"
        )
    return planner


def run_attempt(env: TrialEnv, planner: Any, packed: bool) -> tuple[Attempt, AttemptTrace]:
    """Perceive, plan, motion-plan and execute one grasp (module docstring)."""
    from hsqbench.planner.api import PlanningContext

    cfg, rec, d = env.config, env.recorder, env.data
    trace = AttemptTrace()
    t0 = time.perf_counter()
    try:
        obs = env.observe()
    except SimUnstable as exc:
        return Attempt(Outcome.SIM_UNSTABLE, detail=str(exc)), trace
    points = np.asarray(obs.points)
    trace.n_points = len(points)
    perception_s = time.perf_counter() - t0
    if rec.enabled:
        rec.on_observation(obs)
    truth = env.truth()
    trace.graspable_objects = env.graspable_objects(truth)
    presented = {
        "graspable": None if trace.graspable_objects is None else bool(trace.graspable_objects)
    }
    if len(env.info.objects) == 1:
        only = env.info.objects[0]
        presented["object_pose"] = env.object_pose(only)
        presented["resting_pose"] = env.info.resting_poses.get(only, -1)
    if len(points) < cfg.min_cloud_points and not getattr(planner, "privileged", False):
        attempt = Attempt(
            Outcome.NO_GRASP_FOUND,
            perception_s=perception_s,
            detail=f"the cloud has {len(points)} points (fewer than {cfg.min_cloud_points})",
            **presented,
        )
        rec.on_outcome(attempt) if rec.enabled else None
        return attempt, trace

    t0 = time.perf_counter()
    context = PlanningContext(
        support_plane=tuple(float(x) for x in env.info.support_plane),
        packed=packed,
        seed=int(env.rngs["planner"].integers(2**31)),
        camera_positions=np.asarray(obs.camera_positions),
        workspace_bounds=(np.asarray(env.info.workspace_min), np.asarray(env.info.workspace_max)),
        truth=truth if getattr(planner, "privileged", False) else None,
    )
    plan = planner.plan(points, context)
    planning_s = time.perf_counter() - t0
    if rec.enabled:
        rec.on_plan(plan)
    grasps = plan.grasps
    common = {
        "n_grasps": len(grasps),
        "perception_s": perception_s,
        "planning_s": planning_s,
        **presented,
    }
    if not len(grasps):
        attempt = Attempt(
            Outcome.NO_GRASP_FOUND, detail=plan.reason or "the planner returned no grasp", **common
        )
        rec.on_outcome(attempt) if rec.enabled else None
        return attempt, trace

    t0 = time.perf_counter()
    motion, rank, reasons = None, -1, []
    clear_z = float(points[:, 2].max()) + cfg.execution.hover_clearance_m
    cloud = voxel_downsample(points, cfg.execution.cloud_voxel_m).points
    seen: set[tuple] = set()
    for r in _execution_order(grasps, cfg.max_ranks * TIE_WINDOW):
        if trace.ranks_tried >= cfg.max_ranks:
            break
        key = _grasp_key(grasps[r])
        if key in seen:  # a duplicate of a grasp that already failed (planners emit twins)
            continue
        seen.add(key)
        motion, reason = plan_motion(env, grasps[r], clear_z, cloud)
        trace.ranks_tried += 1
        if motion is not None:
            rank = r
            break
        reasons.append(f"rank {r}: {reason}")
    trace.ik_s = time.perf_counter() - t0
    top = grasps[0]
    intended = env.probe.nearest_object(d, np.asarray(top.position))

    def pose_of(name: str) -> dict[str, Any]:
        # The target's pose as perceived (nothing has moved yet); isolated scenes have it already.
        if "object_pose" in presented or not name:
            return {}
        return {
            "object_pose": env.object_pose(name),
            "resting_pose": env.info.resting_poses.get(name, -1),
        }

    if motion is None:
        attempt = Attempt(
            Outcome.UNREACHABLE,
            target=intended,
            score=float(top.score),
            factors=dict(top.factors),
            width_m=float(top.width),
            execution_s=trace.ik_s,
            detail=reasons[0] if len(reasons) == 1 else f"{len(reasons)} grasps: {reasons[0]}",
            **common,
            **pose_of(intended),
        )
        rec.on_outcome(attempt) if rec.enabled else None
        return attempt, trace

    grasp = grasps[rank]
    trace.flipped = motion.flipped
    if rec.enabled:
        rec.on_grasp(grasp, rank)
    intended = env.probe.nearest_object(d, np.asarray(grasp.position))
    common.update(pose_of(intended))
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
        rank_executed=rank,
        score=float(grasp.score),
        factors={k: float(v) for k, v in grasp.factors.items()},
        width_m=float(grasp.width),
        execution_s=time.perf_counter() - t0,
        detail=res.detail,
        **common,
    )
    if rec.enabled:
        rec.on_outcome(attempt)
    return attempt, trace


def _return_home(env: TrialEnv) -> None:
    """Open the hand, rise, and go home (between the attempts of a packed round)."""
    st, panda, d = env.stepper, env.panda, env.data
    st.phase = "home"
    st.open_hand(panda.max_width() - env.config.execution.release_gap_m)
    env.ik.sync(d)
    here = Pose(*panda.tcp_pose(d))
    up = env.ik.solve(
        here.moved([0.0, 0.0, env.config.execution.retreat_height_m]), panda.arm_q(d), restarts=1
    )
    if up.ok:
        st.move_joints(up.q, settle=False)
    st.move_joints(panda.home_arm_q)


def _planner_name(planner: Any) -> str:
    return (
        planner
        if isinstance(planner, str)
        else str(getattr(planner, "name", type(planner).__name__))
    )


def run_isolated_trial(
    object: str | ObjectLike,
    seed: int,
    planner: Any = "hsq",
    config: TrialConfig | None = None,
    *,
    recorder: Recorder | None = None,
    traces: list[AttemptTrace] | None = None,
) -> TrialResult:
    """One object at the seed's random upright pose, one attempt (the paper's isolated protocol).

    Args:
        object: an object name (``hsqbench.assets.library``) or an object.
        seed: the only source of randomness.
        planner: a planner name (``hsqbench.planner.planner_names()``) or a ``Planner``.
        config: default ``configs/trial.yaml``.
        recorder: episode recorder (default: none).
        traces: if given, the attempt's :class:`AttemptTrace` is appended to it.
    """
    cfg = config if config is not None else load_trial_config()
    plan = resolve_planner(planner, cfg)
    with TrialEnv.build("isolated", object, seed, cfg, recorder) as env:
        attempt, trace = run_attempt(env, plan, packed=False)
        trace.scene_build_s = env.info.build_time_s
        name = env.info.objects[0]
    if traces is not None:
        traces.append(trace)
    return TrialResult(object=name, seed=seed, planner=_planner_name(planner), attempts=[attempt])


def run_packed_round(
    objects: Sequence[str | ObjectLike] | None,
    seed: int,
    planner: Any = "hsq",
    config: TrialConfig | None = None,
    *,
    recorder: Recorder | None = None,
    traces: list[AttemptTrace] | None = None,
    kind: str = "packed",
) -> RoundResult:
    """A packed round: the objects placed apart (drawn by seed when ``objects`` is None), then
    attempts until no object is left on the table or ``max_consecutive_failures`` in a row.

    Objects in the bin after an attempt are cleared; objects that fell off the table are removed
    but not cleared. ``h_delta`` is off (``PlanningContext.packed``). ``kind="pile"``: the same
    round on a pile scene (:mod:`hsqbench.sim.scene.pile`), which also ends at the first attempt
    without a grasp when ``pile.stop_on_no_grasp`` is set.
    """
    if kind not in ("packed", "pile"):
        raise ValueError(f"a clutter-removal round is packed or pile, got {kind!r}")
    cfg = config if config is not None else load_trial_config()
    plan = resolve_planner(planner, cfg)
    attempts: list[Attempt] = []
    cleared: list[str] = []
    graspable: list[str] | None = None
    with TrialEnv.build(kind, objects, seed, cfg, recorder) as env:
        failures = 0
        for i in range(cfg.packed.max_attempts):
            if not env.objects_on_table():
                break
            attempt, trace = run_attempt(env, plan, packed=True)
            if i == 0:
                trace.scene_build_s = env.info.build_time_s
                graspable = trace.graspable_objects
            attempts.append(attempt)
            if traces is not None:
                traces.append(trace)
            if attempt.outcome == Outcome.SIM_UNSTABLE:
                break
            try:
                _return_home(env)
            except SimUnstable as exc:
                attempt.detail += f"; then the simulation became unstable going home: {exc}"
                break
            for name in env.info.objects:
                if name in env.removed:
                    continue
                if env.probe.in_bin(env.data, name):
                    cleared.append(name)
                    env.remove(name)
                elif not env.probe.on_table(env.data, name):
                    env.remove(name)
            failures = 0 if attempt.success else failures + 1
            if failures >= cfg.packed.max_consecutive_failures:
                break
            if (
                kind == "pile"
                and cfg.pile.stop_on_no_grasp
                and attempt.outcome == Outcome.NO_GRASP_FOUND
            ):
                break
        names = list(env.info.objects)
    return RoundResult(
        objects=names,
        seed=seed,
        planner=_planner_name(planner),
        attempts=attempts,
        objects_cleared=cleared,
        objects_graspable=graspable,
    )
