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
    close_time_s: float = 0.6
    carrier_stiffness_n_per_m: float = 1.0e5
    carrier_damping_ns_per_m: float = 1.2e3
    max_slip_m: float = 0.005


@dataclass(frozen=True)
class GraspSpec:
    """A top-down grasp in the object frame.

    Attributes:
        yaw_rad: angle of the closing axis from the object's x axis, about z.
        height_m: height of the grasp centre (TCP) above the object's base.
        offset_m: (x, y) of the grasp centre in the object frame.
    """

    yaw_rad: float = 0.0
    height_m: float = 0.05
    offset_m: tuple[float, float] = (0.0, 0.0)


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


def _hand_pose(grasp: GraspSpec, tcp_offset_m: float) -> tuple[np.ndarray, np.ndarray]:
    """World pose (pos, quat) of the hand body for a top-down grasp (approach = -z)."""
    c, s = np.cos(grasp.yaw_rad), np.sin(grasp.yaw_rad)
    x = np.array([c, s, 0.0])
    z = np.array([0.0, 0.0, -1.0])
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
    carrier.add_joint(name="lift", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0.0, 0.0, -1.0])
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
