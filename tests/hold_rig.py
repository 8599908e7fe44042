"""Hold test: does the hand keep an object when it lifts it like the arm would?

A fast rig with the same hand, actuator, pads and physics options as the scene: the Franka Hand
(from :func:`hsqbench.sim.robot.load_panda_spec`, so with every modification) hangs from a
carrier body on a vertical slide, driven by a stiff position servo. The object stands on a table
plane between the open fingers; the hand closes, then the carrier follows a bang-bang lift
(constant acceleration ``a`` up to half the height, ``-a`` after), and holds. Slip is the
displacement of the object's centre of mass in the hand frame between the end of closing and the
end of the hold, in metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from hsqbench.config import load_config
from hsqbench.sim.objects import ObjectLike, add_object_body
from hsqbench.sim.physics import PhysicsConfig, apply_physics, load_physics_config
from hsqbench.sim.robot import HAND_BODY, Hand, RobotConfig, load_panda_spec, load_robot_config


@dataclass(frozen=True)
class HoldConfig:
    """Lift profile of the hold test.

    Attributes:
        accel_mps2: lift acceleration (and deceleration), m/s^2.
        lift_height_m: lift distance, m.
        hold_time_s: time held still at the top, s.
        close_time_s: time given to close and build up the grasp force, s.
        carrier_stiffness_n_per_m, carrier_damping_ns_per_m: gains of the carrier's servo.
        max_slip_m: largest slip that counts as held.
    """

    accel_mps2: float = 1.5
    lift_height_m: float = 0.15
    hold_time_s: float = 2.0
    close_time_s: float = 1.2
    carrier_stiffness_n_per_m: float = 1.0e5
    carrier_damping_ns_per_m: float = 1.2e3
    max_slip_m: float = 0.005


@dataclass(frozen=True)
class GraspSpec:
    """A grasp from above in the object frame.

    Attributes:
        yaw_rad: angle of the closing axis from the object's x axis, about z.
        height_m: height of the grasp centre (TCP) above the object's base.
        offset_m: (x, y) of the grasp centre in the object frame.
        pitch_rad: tilt of the hand about the horizontal axis perpendicular to the closing axis;
            the closing axis becomes ``cos(pitch) c + sin(pitch) z`` (``c`` the yawed horizontal
            axis, ``z`` up) and the approach stays perpendicular to it. 0 is straight down.
    """

    yaw_rad: float = 0.0
    height_m: float = 0.05
    offset_m: tuple[float, float] = (0.0, 0.0)
    pitch_rad: float = 0.0


@dataclass
class HoldResult:
    """Outcome of one hold test (lengths in metres, forces in newtons)."""

    name: str
    slip_m: float
    lifted_m: float
    width_m: float
    finger_force_n: np.ndarray = field(default_factory=lambda: np.zeros(2))
    held: bool = False


def load_hold_config(path: str | Path | None = "hold") -> HoldConfig:
    """Load ``configs/hold.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(HoldConfig, path)


@dataclass(frozen=True)
class FinderConfig:
    """Search for a top-down test grasp (:func:`find_top_down_grasp`); lengths in metres.

    Attributes:
        spacing_m: surface sampling and position grid spacing.
        yaw_steps: closing-axis angles tried in [0, pi).
        max_width_m: widest object slice the hand may close on (opening 0.08 less a margin).
        pad_half_m: half size of the pad region (across and along the fingers).
        finger_len_m: finger length above the grasp centre that must clear the object.
        finger_thick_m: finger thickness outside the contact faces.
        palm_clearance_m: height of the palm above the grasp centre.
        min_height_m: lowest grasp centre above the base (fingertips clear the table).
        max_face_tilt_m: how far the slice's ends may differ across the pad (contact faces
            square to the closing axis, so the squeeze does not push the object sideways), and
            how far its middle may move between the pad's lower and upper halves (a wall leaning
            out of the pad plane, which the squeeze would turn; see :func:`_lean`).
        pitch_step_rad, max_pitch_rad: tilts tried, in these steps up to this bound on either
            side, when no straight-down grasp has square faces (the flared wall of a bowl).
    """

    spacing_m: float = 0.004
    yaw_steps: int = 8
    max_width_m: float = 0.074
    pad_half_m: float = 0.0085
    finger_len_m: float = 0.045
    finger_thick_m: float = 0.012
    palm_clearance_m: float = 0.035
    min_height_m: float = 0.02
    max_face_tilt_m: float = 0.002
    # 2.5 deg: a face tilted by half a step is off by 0.2 mm across a pad half (8.5 mm). 30 deg:
    # the YCB bowl's wall leans 20 deg (its hulls 23 deg) from vertical where the pads fit.
    pitch_step_rad: float = float(np.radians(2.5))
    max_pitch_rad: float = float(np.radians(30.0))


def find_top_down_grasp(obj: ObjectLike, finder: FinderConfig | None = None) -> GraspSpec:
    """A grasp from above on ``obj`` for the hold test, from its collision hulls.

    Candidates: a grid of grasp centres and closing-axis yaws, first with the hand straight down.
    In the hand's frame (u along the closing axis, v across the pads, w up the fingers) the
    object's samples within the pad region (|v| and |w| below ``pad_half_m``) form the slice the
    pads close on; a candidate is kept when that slice is narrower than ``max_width_m``, ends in
    faces square to the closing axis across the pads and does not lean up them, nothing else of
    the object lies in the fingers' path (the columns beside the slice up to the open width, from
    the pads up to ``finger_len_m``) or under the palm, and the fingertips and palm clear the
    table. The grasp is centred on its slice; the one closest to the centre of mass wins.

    When no straight-down candidate passes, the hand is tilted about the axis across the pads
    (``pitch_step_rad`` steps up to ``max_pitch_rad``, both ways), as an arm grasping a sloped
    wall would: a pinch on a wall leaning out of the pad plane turns the object in the hand until
    the wall lies flat on the pads (the YCB bowl turned 23 deg at its rim, its centre of mass
    24 mm). Among tilted candidates the least leaning slice wins, then the closest to the centre
    of mass.

    Raises:
        ValueError: when no candidate passes (the object does not fit the hand from above).
    """
    import trimesh

    f = finder or FinderConfig()
    hulls = [trimesh.load(p, force="mesh") for p in obj.collision_meshes]
    pts = _solid_points(hulls, f.spacing_m)
    ext = np.asarray(obj.extents)
    best = _best_grasp(pts, obj, f, 0.0)
    if best is None:
        steps = np.arange(1, round(f.max_pitch_rad / f.pitch_step_rad) + 1) * f.pitch_step_rad
        tilted = [_best_grasp(pts, obj, f, sign * p) for p in steps for sign in (1.0, -1.0)]
        best = min((b for b in tilted if b is not None), key=lambda b: b[0], default=None)
    if best is None:
        raise ValueError(f"{obj.name}: no top-down grasp fits the hand (extents {ext.round(3)} m)")
    return best[1]


def _best_grasp(
    pts: np.ndarray, obj: ObjectLike, f: FinderConfig, pitch: float
) -> tuple[tuple[float, float], GraspSpec] | None:
    """The best candidate with the hand at ``pitch`` (see :func:`find_top_down_grasp`), with its
    cost (the slice's lean in metres, rounded to 0.1 mm, or 0 straight down; distance to the
    centre of mass), or ``None``."""
    ext = np.asarray(obj.extents)
    com = np.asarray(obj.com)
    step = 2 * f.spacing_m
    half_open = 0.04  # the fingers start fully open (Franka Hand: 40 mm travel each)
    cp, sp = np.cos(pitch), np.sin(pitch)
    up = np.array([0.0, 0.0, 1.0])
    best: tuple[tuple[float, float], GraspSpec] | None = None
    for yaw in np.arange(f.yaw_steps) * np.pi / f.yaw_steps:
        c = np.array([np.cos(yaw), np.sin(yaw), 0.0])
        perp = np.array([-c[1], c[0], 0.0])
        x_axis, w_axis = cp * c + sp * up, -sp * c + cp * up
        u_all, v_all, h_all = pts @ x_axis, pts @ perp, pts @ w_axis
        if pitch == 0.0:
            heights = np.arange(f.min_height_m, ext[2] - f.pad_half_m / 2, step)
        else:  # the fingertip clearance below decides which heights reach too low
            heights = np.arange(h_all.min(), h_all.max() - f.pad_half_m / 2, step)
        gx = np.arange(-ext[0] / 2, ext[0] / 2 + 1e-9, step)
        gy = np.arange(-ext[1] / 2, ext[1] / 2 + 1e-9, step)
        for v0 in np.unique(np.round(np.add.outer(gx * perp[0], gy * perp[1]).ravel(), 4)):
            near = np.abs(v_all - v0) < 0.05  # under the palm's footprint
            u_n, v_n, z_n = u_all[near], v_all[near] - v0, h_all[near]
            strip = np.abs(v_n) < f.pad_half_m
            u_s, v_s, z_s = u_n[strip], v_n[strip], z_n[strip]
            for z in heights:
                w = z_s - z
                slab = np.abs(w) < f.pad_half_m
                if slab.sum() < 3:
                    continue
                for umin, umax in _clusters(np.sort(u_s[slab]), f.spacing_m * 1.5):
                    width = umax - umin
                    if width > f.max_width_m:
                        continue
                    uc = 0.5 * (umin + umax)
                    # Lowest fingertip corner (open fingers, pad bottom) above the table, by as
                    # much as straight down at the lowest allowed height; the palm's lower edge
                    # (the palm region of the check below, 11 cm either side) above the table.
                    tip_z = (
                        uc * sp
                        + z * cp
                        - f.pad_half_m * cp
                        - (half_open + f.finger_thick_m) * abs(sp)
                    )
                    palm_z = uc * sp + z * cp + f.palm_clearance_m * cp - 0.11 * abs(sp)
                    if tip_z < f.min_height_m - f.pad_half_m - 1e-9 or palm_z < 0.0:
                        continue
                    grasped = slab & (u_s >= umin) & (u_s <= umax)
                    gu = u_s[grasped] - uc
                    if not _faces_square(gu, v_s[grasped], f.max_face_tilt_m):
                        continue
                    lean = _lean(gu, w[grasped])
                    if lean >= f.max_face_tilt_m:
                        continue
                    du = np.abs(u_s - uc)
                    in_finger_path = (
                        (w > -f.pad_half_m)
                        & (w < f.finger_len_m)
                        & (du > width / 2 + f.spacing_m)
                        & (du < half_open + f.finger_thick_m)
                    )
                    under_palm = (z_n - z >= f.palm_clearance_m) & (np.abs(u_n - uc) < 0.11)
                    if in_finger_path.any() or under_palm.any():
                        continue
                    centre = uc * x_axis + v0 * perp + z * w_axis
                    cost = (
                        0.0 if pitch == 0.0 else round(lean, 4),
                        float(np.linalg.norm(centre - com)),
                    )
                    if best is None or cost < best[0]:
                        grasp = GraspSpec(
                            float(yaw),
                            float(centre[2]),
                            (float(centre[0]), float(centre[1])),
                            float(pitch),
                        )
                        best = (cost, grasp)
    return best


def _solid_points(hulls: list, spacing: float) -> np.ndarray:
    """Points filling the union of convex hulls: a grid kept by the half-space test, plus
    surface samples so thin walls are not missed."""
    import trimesh

    lo = np.min([h.bounds[0] for h in hulls], axis=0)
    hi = np.max([h.bounds[1] for h in hulls], axis=0)
    axes = [np.arange(a, b + spacing, spacing) for a, b in zip(lo, hi, strict=True)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = np.zeros(len(grid), dtype=bool)
    for h in hulls:
        normals = h.face_normals
        offsets = np.einsum("ij,ij->i", normals, h.triangles[:, 0])
        inside |= np.all(grid @ normals.T <= offsets + 1e-9, axis=1)
    surface = [
        trimesh.sample.sample_surface_even(h, max(50, int(h.area / spacing**2)), seed=0)[0]
        for h in hulls
    ]
    return np.concatenate([grid[inside], *surface, *(h.vertices for h in hulls)])


def _faces_square(u: np.ndarray, v: np.ndarray, tol: float) -> bool:
    """Whether the grasped slice ends in faces square to the closing axis: its outermost points
    on the two sides of the strip's middle line differ by less than ``tol`` at each end."""
    left, right = v < 0, v >= 0
    if left.sum() == 0 or right.sum() == 0:
        return False
    return bool(
        abs(u[left].min() - u[right].min()) < tol and abs(u[left].max() - u[right].max()) < tol
    )


def _lean(u: np.ndarray, w: np.ndarray) -> float:
    """How far the middle of the grasped slice moves along the closing axis between its lower
    and upper halves (``w < 0``, ``w >= 0``), in metres; infinite when a half is empty.

    Both ends leaning the same way (a wall sloping out of the pad plane) meet the pads at
    opposite edges, and the squeeze turns the object until the wall lies flat on them; a taper
    (ends leaning opposite ways, a bottle's shoulder) leaves the middle in place and does not.
    """
    low, high = w < 0, w >= 0
    if low.sum() == 0 or high.sum() == 0:
        return float("inf")
    mid_low = 0.5 * (u[low].min() + u[low].max())
    mid_high = 0.5 * (u[high].min() + u[high].max())
    return float(abs(mid_high - mid_low))


def _clusters(u_sorted: np.ndarray, gap: float) -> list[tuple[float, float]]:
    """Runs of sorted values whose consecutive gaps are below ``gap``: (first, last) each."""
    breaks = np.flatnonzero(np.diff(u_sorted) > gap)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [len(u_sorted) - 1]])
    return [(float(u_sorted[a]), float(u_sorted[b])) for a, b in zip(starts, ends, strict=True)]


def _hand_pose(grasp: GraspSpec, tcp_offset_m: float) -> tuple[np.ndarray, np.ndarray]:
    """World pose (pos, quat) of the hand body for a grasp from above (approach = -z, tilted by
    ``grasp.pitch_rad`` about the axis across the pads)."""
    c, s = np.cos(grasp.yaw_rad), np.sin(grasp.yaw_rad)
    cp, sp = np.cos(grasp.pitch_rad), np.sin(grasp.pitch_rad)
    x = np.array([cp * c, cp * s, sp])
    z = -np.array([-sp * c, -sp * s, cp])
    r_tcp = np.column_stack([x, np.cross(z, x), z])
    # TCP = hand * Rz(+90 deg), so hand = TCP * Rz(-90 deg): hand x = -TCP y, hand y = TCP x.
    r_hand = np.column_stack([-r_tcp[:, 1], r_tcp[:, 0], r_tcp[:, 2]])
    p_tcp = np.array([grasp.offset_m[0], grasp.offset_m[1], grasp.height_m])
    p_hand = p_tcp - r_hand @ np.array([0.0, 0.0, tcp_offset_m])
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, r_hand.reshape(-1))
    return p_hand, quat


def build_hold_rig(
    obj: ObjectLike,
    grasp: GraspSpec,
    robot: RobotConfig,
    physics: PhysicsConfig,
    hold: HoldConfig,
) -> tuple[mujoco.MjModel, mujoco.MjData]:
    """The rig model: floor, object at the origin, hand on a vertical slide above it."""
    spec = mujoco.MjSpec()
    spec.modelname = f"hold_{obj.name}"
    apply_physics(spec, physics)
    floor = spec.worldbody.add_geom(
        name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1.0, 1.0, 0.01]
    )
    physics.table.apply(floor)
    add_object_body(
        spec.worldbody, spec, obj, "object", np.zeros(3), np.array([1.0, 0, 0, 0]), physics.objects
    )
    p_hand, q_hand = _hand_pose(grasp, robot.tcp_offset_m)
    carrier = spec.worldbody.add_body(name="carrier", pos=list(p_hand), quat=list(q_hand))
    r_hand = np.zeros(9)
    mujoco.mju_quat2Mat(r_hand, q_hand)
    # The lift is straight up in the world, also when the hand is tilted (axis in carrier frame).
    up_in_carrier = r_hand.reshape(3, 3).T @ np.array([0.0, 0.0, 1.0])
    carrier.add_joint(name="lift", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(up_in_carrier))
    carrier.mass = 1.0
    carrier.inertia = [0.01, 0.01, 0.01]
    carrier.explicitinertial = True
    carrier.gravcomp = 1.0
    k, c = hold.carrier_stiffness_n_per_m, hold.carrier_damping_ns_per_m
    spec.add_actuator(
        name="lift",
        trntype=mujoco.mjtTrn.mjTRN_JOINT,
        target="lift",
        gainprm=[k] + [0.0] * 9,
        biastype=mujoco.mjtBias.mjBIAS_AFFINE,
        biasprm=[0.0, -k, -c] + [0.0] * 7,
    )
    panda = load_panda_spec(robot)
    frame = carrier.add_frame()
    hand = frame.attach_body(panda.body(HAND_BODY), robot.prefix, "")
    hand.pos = [0.0, 0.0, 0.0]  # the carrier's pose is the hand's pose (not link7's offset)
    hand.quat = [1.0, 0.0, 0.0, 0.0]
    model = spec.compile()
    return model, mujoco.MjData(model)


def _lift_target(t: float, hold: HoldConfig) -> float:
    """Bang-bang lift: height (m) at time t after the lift starts."""
    h, a = hold.lift_height_m, hold.accel_mps2
    t_half = np.sqrt(h / a)
    if t <= t_half:
        return 0.5 * a * t * t
    if t <= 2 * t_half:
        dt = 2 * t_half - t
        return h - 0.5 * a * dt * dt
    return h


def run_hold_test(
    obj: ObjectLike,
    grasp: GraspSpec,
    robot: RobotConfig | None = None,
    physics: PhysicsConfig | None = None,
    hold: HoldConfig | None = None,
) -> HoldResult:
    """Close on ``obj`` with ``grasp``, lift and hold; measure slip and finger force."""
    robot = robot or load_robot_config()
    physics = physics or load_physics_config()
    hold = hold or load_hold_config()
    model, data = build_hold_rig(obj, grasp, robot, physics, hold)
    panda = Hand(model, robot.prefix)
    obj_id = model.body("object").id
    lift = model.actuator("lift").id
    mujoco.mj_resetData(model, data)
    data.qpos[panda.finger_qpos_adr] = panda.max_width() / 2.0
    panda.open_gripper(data)
    panda.sync_gripper_target(data)
    mujoco.mj_forward(model, data)

    dt = model.opt.timestep
    panda.close_gripper(data)
    for _ in range(round(hold.close_time_s / dt)):
        mujoco.mj_step(model, data)
    force = panda.finger_forces(data, obj_id)
    width = panda.gripper_width(data)
    start = _com_in_hand(data, panda, obj_id)
    z0 = data.xipos[obj_id, 2]

    t_lift = 2.0 * np.sqrt(hold.lift_height_m / hold.accel_mps2)
    n = round((t_lift + hold.hold_time_s) / dt)
    for i in range(n):
        data.ctrl[lift] = _lift_target((i + 1) * dt, hold)
        mujoco.mj_step(model, data)
    slip = float(np.linalg.norm(_com_in_hand(data, panda, obj_id) - start))
    lifted = float(data.xipos[obj_id, 2] - z0)
    held = bool(slip < hold.max_slip_m and lifted > hold.lift_height_m - hold.max_slip_m)
    return HoldResult(obj.name, slip, lifted, width, force, held)


def _com_in_hand(data: mujoco.MjData, panda: Hand, obj_id: int) -> np.ndarray:
    r = data.xmat[panda.hand_body_id].reshape(3, 3)
    return r.T @ (data.xipos[obj_id] - data.xpos[panda.hand_body_id])
