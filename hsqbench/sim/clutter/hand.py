"""The free-floating Franka Hand of VGN/GIGA's clutter removal, in MuJoCo.

VGN and GIGA (``src/vgn/simulation.py``, class ``Gripper``) load a Panda hand alone and move it
with a fixed constraint between the world and the hand body (``pybullet.JOINT_FIXED``, its
child pivot moved along the path). Here: Menagerie's hand (``franka_emika_panda/hand.xml``)
with every change :func:`hsqbench.sim.robot.apply_modifications` makes to the arm's hand (the
70 N force-limited finger servo, the pads' contact, the ``tcp`` site between the pads), on a
free joint, welded to a mocap body that the execution moves. Width sensing is the arm hand's
(:meth:`hsqbench.sim.robot.Hand.gripper_width`). The arm's gravity compensation does not apply
(there is no arm); the weld carries the hand's weight.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.robot import (
    HAND_BODY,
    TCP_SITE,
    Hand,
    RobotConfig,
    apply_modifications,
)

#: Name prefix of the free hand's elements in a composed scene.
HAND_PREFIX = "hand/"
#: The mocap body the hand is welded to.
MOCAP_BODY = "hand_target"

Array = NDArray[np.float64]


def load_hand_spec(robot: RobotConfig) -> mujoco.MjSpec:
    """Menagerie's hand alone (entry point ``hand`` of the robot's Menagerie model), with the
    arm hand's modifications; no arm, so no gravity compensation of arm links."""
    import mujoco_menagerie as mm

    path = mm.get(robot.menagerie_model).xml("hand")
    spec = mujoco.MjSpec.from_file(str(path))
    for light in list(spec.lights):
        spec.delete(light)
    apply_modifications(spec, dataclasses.replace(robot, gravity_compensation=False))
    return spec


def add_free_hand(spec: mujoco.MjSpec, robot: RobotConfig, park: Array) -> None:
    """Add the hand on a free joint at ``park`` (x, y, z), welded to the mocap body
    :data:`MOCAP_BODY` at the same place (the weld's relative pose is the identity)."""
    hand = load_hand_spec(robot)
    body = hand.body(HAND_BODY)
    body.pos = [0.0, 0.0, 0.0]
    body.quat = [1.0, 0.0, 0.0, 0.0]
    body.add_freejoint(name="free")
    frame = spec.worldbody.add_frame(pos=list(map(float, park)))
    spec.attach(hand, prefix=HAND_PREFIX, frame=frame)
    spec.worldbody.add_body(name=MOCAP_BODY, mocap=True, pos=list(map(float, park)))
    spec.add_equality(
        type=mujoco.mjtEq.mjEQ_WELD,
        objtype=mujoco.mjtObj.mjOBJ_BODY,
        name1=MOCAP_BODY,
        name2=HAND_PREFIX + HAND_BODY,
        # anchor (3), relative position (3), relative quaternion (4), torque scale
        data=[0.0] * 6 + [1.0, 0.0, 0.0, 0.0, 1.0, 0.0],
    )


def _pose_matrix(position: Array, rotation: Array) -> Array:
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = position
    return out


class FreeHand(Hand):
    """Handles into a model with the free hand: its pose by the TCP, contacts, teleporting."""

    def __init__(self, model: mujoco.MjModel) -> None:
        super().__init__(model, HAND_PREFIX)
        self.mocap_id = int(model.body_mocapid[model.body(MOCAP_BODY).id])
        joint = model.body_jntadr[self.hand_body_id]
        self.free_qpos = int(model.jnt_qposadr[joint])
        self.free_dof = int(model.jnt_dofadr[joint])
        # The TCP site in the hand body's frame: the hand pose for a TCP pose follows from it.
        site = model.site(HAND_PREFIX + TCP_SITE)
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, model.site_quat[site.id])
        self.T_hand_tcp = _pose_matrix(model.site_pos[site.id].copy(), rot.reshape(3, 3))
        self.geom_ids = np.flatnonzero(np.isin(model.geom_bodyid, self.body_ids))

    def hand_pose_for(self, tcp_position: Array, tcp_rotation: Array) -> tuple[Array, Array]:
        """(position, quaternion w x y z) of the hand body that puts the TCP at the given pose."""
        T = _pose_matrix(np.asarray(tcp_position, float), np.asarray(tcp_rotation, float))
        T = T @ np.linalg.inv(self.T_hand_tcp)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, T[:3, :3].ravel())
        return T[:3, 3].copy(), quat

    def tcp_position(self, data: mujoco.MjData) -> Array:
        return data.site_xpos[self.tcp_site_id].copy()

    def set_target(self, data: mujoco.MjData, tcp_position: Array, tcp_rotation: Array) -> None:
        """Move the mocap body (the weld pulls the hand after it)."""
        pos, quat = self.hand_pose_for(tcp_position, tcp_rotation)
        data.mocap_pos[self.mocap_id] = pos
        data.mocap_quat[self.mocap_id] = quat

    def teleport(self, data: mujoco.MjData, tcp_position: Array, tcp_rotation: Array) -> None:
        """Put the hand, open and at rest, with its TCP at the pose (their ``Gripper.reset``)."""
        pos, quat = self.hand_pose_for(tcp_position, tcp_rotation)
        data.mocap_pos[self.mocap_id] = pos
        data.mocap_quat[self.mocap_id] = quat
        data.qpos[self.free_qpos : self.free_qpos + 3] = pos
        data.qpos[self.free_qpos + 3 : self.free_qpos + 7] = quat
        data.qvel[self.free_dof : self.free_dof + 6] = 0.0
        width = self.max_width()
        data.qpos[self.finger_qpos_adr] = width / 2.0
        data.qvel[self.finger_dof_adr] = 0.0
        self.set_gripper(data, width)
        self.sync_gripper_target(data)
        mujoco.mj_forward(self.model, data)

    def touching(self, data: mujoco.MjData) -> NDArray[np.int_]:
        """Body ids of everything (objects, table) the hand or its fingers touch now."""
        n = data.ncon
        if n == 0:
            return np.zeros(0, dtype=int)
        geoms = data.contact.geom[:n]
        mine = np.isin(geoms, self.geom_ids)
        hit = mine[:, 0] ^ mine[:, 1]
        other = np.where(mine[:, 0], geoms[:, 1], geoms[:, 0])[hit]
        return np.unique(self.model.geom_bodyid[other])
