"""Poses as the results tables record them: seven numbers ``(x, y, z, qw, qx, qy, qz)``,
position in metres and a unit quaternion (scalar first, MuJoCo's order), and the conversions
to and from a position and rotation matrix."""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray


def pose7(position: ArrayLike, rotation: ArrayLike) -> tuple[float, ...]:
    """``(x, y, z, qw, qx, qy, qz)`` of a position (3,) and a rotation matrix (3, 3); the
    quaternion's sign is chosen with ``qw >= 0`` so one rotation has one record."""
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation, dtype=np.float64).ravel())
    quat = -quat if quat[0] < 0 else quat
    return tuple(float(x) for x in (*np.asarray(position, dtype=float).reshape(3), *quat))


def from_pose7(values: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(position (3,), rotation (3, 3)) of a seven-number pose; the quaternion is normalised
    (a table rounds it).

    Raises:
        ValueError: not seven finite numbers, or a zero quaternion.
    """
    v = np.asarray(values, dtype=float).ravel()
    if v.shape != (7,) or not np.all(np.isfinite(v)):
        raise ValueError(f"a pose is 7 finite numbers (x y z qw qx qy qz), got {v.tolist()}")
    norm = float(np.linalg.norm(v[3:]))
    if norm < 1e-9:
        raise ValueError(f"the pose's quaternion is zero: {v.tolist()}")
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, v[3:] / norm)
    return v[:3].copy(), rotation.reshape(3, 3)


def pose7_in_frame(pose: ArrayLike, frame: ArrayLike) -> tuple[float, ...]:
    """``pose`` (world) expressed in the frame whose world pose is ``frame`` (both seven
    numbers): ``frame^-1 * pose``."""
    p, r = from_pose7(pose)
    fp, fr = from_pose7(frame)
    return pose7(fr.T @ (p - fp), fr.T @ r)
