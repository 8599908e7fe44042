"""Pure pose geometry of a grasp's motion: the lift height, the carry pose over the bin and the
hover / pre-grasp poses (no simulation; numbers in, poses out)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.ik import Pose


def rot_z(angle: float) -> NDArray[np.float64]:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def lift_height(
    min_lift_m: float, bin_wall_top_z: float, carry_clearance_m: float, table_top_z: float
) -> float:
    """TCP rise that brings an object standing on the table above the bin walls plus the
    clearance (objects start on the table: their lowest point is the table top)."""
    need = bin_wall_top_z + carry_clearance_m - table_top_z
    return float(max(min_lift_m, need))


def carry_pose(
    bin_centre_xy: NDArray[np.float64], lifted: Pose, held_xy: NDArray[np.float64]
) -> tuple[Pose, float]:
    """Carry target: the lifted TCP pose turned about the world z axis so that the held point
    ``held_xy`` (object centre, or the grasp point before execution) lands over the bin centre,
    at the same height and with the same tilt. Returns the pose and the turn (rad)."""
    bin_c = np.asarray(bin_centre_xy, float)
    yaw = float(np.arctan2(bin_c[1], bin_c[0]) - np.arctan2(held_xy[1], held_xy[0]))
    yaw = float((yaw + np.pi) % (2 * np.pi) - np.pi)
    rz = rot_z(yaw)
    offset = rz[:2, :2] @ (lifted.position[:2] - held_xy)
    position = np.array([*(bin_c + offset), lifted.position[2]])
    return Pose(position, rz @ lifted.rotation), yaw


def first_pose(
    pose: Pose,
    pregrasp_distance_m: float,
    hand_box: tuple[NDArray[np.float64], NDArray[np.float64]],
    clear_z: float,
) -> tuple[Pose, Pose]:
    """(first, pre): the end of the joint-space move and the pre-grasp pose. ``first`` is the
    hover pose straight above the pre-grasp where the hand's lowest point (the hand's box
    ``(lo, hi)`` in the TCP frame) is at ``clear_z`` (when the pre-grasp is lower than that),
    else the pre-grasp itself."""
    pre = pose.moved(-pregrasp_distance_m * pose.rotation[:, 2])
    lo, hi = hand_box
    row = pose.rotation[2]
    below = float(row @ (0.5 * (lo + hi)) - np.abs(row) @ (0.5 * (hi - lo)))
    descent = clear_z - below - pre.position[2]
    return (pre.moved([0.0, 0.0, descent]) if descent > 0 else pre), pre
