"""Pinhole geometry of MuJoCo depth cameras: intrinsics, poses, back-projection.

Conventions (every function here uses them):

- **Optical frame** (OpenCV, "RDF"): x right, y down, z forward along the viewing direction.
  A MuJoCo camera's own frame is x right, y up, looking along -z ("RUB"); the optical frame is
  that frame turned by pi about its x axis: ``R_world_optical = cam_xmat @ diag(1, -1, -1)``.
- **Pose** ``T_world_camera``: (4, 4) homogeneous transform taking optical-frame points to the
  world, ``p_world = R p_cam + t``; ``t`` is the optical centre in the world.
- **Pixels**: ``u`` = column (right), ``v`` = row (down), row 0 at the top of the image, and
  integer coordinates at pixel *centres* (OpenCV). Tools that put integer coordinates at pixel
  corners (Rerun's ``Pinhole`` defaults its principal point to ``(W / 2, H / 2)``) need
  ``cx + 0.5, cy + 0.5``.
- **Depth**: planar depth ``z`` in metres (the optical-frame z of the surface point, not the
  distance along the ray), ``0`` where there is no measurement.

MuJoCo projects with a vertical field of view ``fovy`` onto square pixels, so
``f = (H / 2) / tan(fovy / 2)`` for both axes, and the image plane spans the full viewport
edges, so the principal point lies at the image centre ``((W - 1) / 2, (H - 1) / 2)``.
"""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Rotation from the optical frame (x right, y down, z forward) to MuJoCo's camera frame
#: (x right, y up, z backward); its own inverse.
OPTICAL_TO_MUJOCO = np.diag([1.0, -1.0, -1.0])


def intrinsics_from_fovy(fovy_deg: float, width_px: int, height_px: int) -> Array:
    """(3, 3) camera matrix ``K`` of a MuJoCo camera (square pixels, centred principal point).

    ``fx = fy = (H / 2) / tan(fovy / 2)``, ``cx = (W - 1) / 2``, ``cy = (H - 1) / 2``.
    """
    if not 0.0 < fovy_deg < 180.0:
        raise ValueError(f"fovy must lie in (0, 180) degrees, got {fovy_deg}")
    if width_px < 1 or height_px < 1:
        raise ValueError(f"image size must be positive, got {width_px} x {height_px} px")
    f = 0.5 * height_px / np.tan(0.5 * np.deg2rad(fovy_deg))
    return np.array([[f, 0.0, 0.5 * (width_px - 1)], [0.0, f, 0.5 * (height_px - 1)], [0, 0, 1]])


def camera_intrinsics(model: mujoco.MjModel, cam_id: int) -> tuple[Array, int, int]:
    """``(K, width_px, height_px)`` of camera ``cam_id`` from its ``fovy`` and ``resolution``.

    Raises:
        ValueError: a camera without a ``resolution`` attribute, an orthographic camera, or one
            whose projection is given by ``sensorsize``/``focal`` (not supported here).
    """
    name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, cam_id) or f"#{cam_id}"
    width, height = (int(x) for x in model.cam_resolution[cam_id])
    if width <= 1 and height <= 1:
        raise ValueError(
            f'camera {name!r} has no image size: give it resolution="W H" in the model'
        )
    if np.any(model.cam_sensorsize[cam_id] > 0):
        raise ValueError(
            f"camera {name!r} defines sensorsize/focal intrinsics; only fovy cameras are supported"
        )
    if model.cam_projection[cam_id] != mujoco.mjtProjection.mjPROJ_PERSPECTIVE:
        raise ValueError(f"camera {name!r} is not a perspective camera")
    return intrinsics_from_fovy(float(model.cam_fovy[cam_id]), width, height), width, height


def camera_pose(data: mujoco.MjData, cam_id: int) -> Array:
    """``T_world_camera`` (4, 4) of camera ``cam_id`` (optical frame), from ``cam_xpos`` and
    ``cam_xmat`` (valid after ``mj_forward`` or ``mj_kinematics``)."""
    pose = np.eye(4)
    pose[:3, :3] = data.cam_xmat[cam_id].reshape(3, 3) @ OPTICAL_TO_MUJOCO
    pose[:3, 3] = data.cam_xpos[cam_id]
    return pose


def backproject(depth_m: NDArray[np.floating], K: Array) -> Array:
    """(H, W, 3) optical-frame points of a depth image: ``X = (u - cx) z / fx``,
    ``Y = (v - cy) z / fy``, ``Z = z``. Pixels with ``z = 0`` map to the origin."""
    depth = np.asarray(depth_m, dtype=np.float64)
    if depth.ndim != 2:
        raise ValueError(f"depth must be an (H, W) image, got shape {depth.shape}")
    h, w = depth.shape
    x = (np.arange(w) - K[0, 2]) / K[0, 0]
    y = (np.arange(h) - K[1, 2]) / K[1, 1]
    return np.stack([depth * x[None, :], depth * y[:, None], depth], axis=-1)


def project(points_cam: Array, K: Array) -> Array:
    """(N, 2) pixel coordinates ``(u, v)`` of optical-frame points (z > 0)."""
    p = np.asarray(points_cam, dtype=np.float64)
    return np.column_stack(
        [K[0, 0] * p[:, 0] / p[:, 2] + K[0, 2], K[1, 1] * p[:, 1] / p[:, 2] + K[1, 2]]
    )


def transform_points(T: Array, points: Array) -> Array:
    """Apply a (4, 4) homogeneous transform to (N, 3) points."""
    # einsum, not ``@``: a BLAS call on an (N, 3) x (3, 3) product is several times slower when
    # OpenBLAS threads compete for a loaded CPU.
    return np.einsum("nj,ij->ni", np.asarray(points, dtype=np.float64), T[:3, :3]) + T[:3, 3]


def invert_pose(T: Array) -> Array:
    """Inverse of a rigid (4, 4) transform."""
    inv = np.eye(4)
    inv[:3, :3] = T[:3, :3].T
    inv[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return inv


def box_roi(
    T_world_camera: Array,
    K: Array,
    width_px: int,
    height_px: int,
    lo: Array,
    hi: Array,
    pad_px: int,
) -> tuple[int, int, int, int]:
    """Image rectangle ``(v0, v1, u0, u1)`` (rows ``v0:v1``, columns ``u0:u1``) holding the
    projection of the world box ``[lo, hi]``, grown by ``pad_px`` and clipped to the image.
    The whole image when a corner of the box lies behind the camera."""
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])]
    )
    cam = transform_points(invert_pose(T_world_camera), corners)
    if np.any(cam[:, 2] <= 0):
        return 0, height_px, 0, width_px
    uv = project(cam, K)
    u0, v0 = np.floor(uv.min(axis=0)).astype(int) - pad_px
    u1, v1 = np.ceil(uv.max(axis=0)).astype(int) + pad_px + 1
    u0, u1 = int(np.clip(u0, 0, width_px)), int(np.clip(u1, 0, width_px))
    v0, v1 = int(np.clip(v0, 0, height_px)), int(np.clip(v1, 0, height_px))
    return v0, v1, u0, u1


def crop_intrinsics(K: Array, v0: int, u0: int) -> Array:
    """Intrinsics of the sub-image whose top-left pixel is ``(v0, u0)`` of the full image."""
    out = np.array(K, dtype=np.float64)
    out[0, 2] -= u0
    out[1, 2] -= v0
    return out
