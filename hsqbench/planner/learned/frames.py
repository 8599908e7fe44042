"""Pure conversions between the harness and Contact-GraspNet (numpy only, no torch).

Harness: world metres, z up; a :class:`~hsqbench.planner.grasp.Grasp` has ``P_G`` (the point
midway between the pads) and the rotation columns (closing, third, approach), third = approach x
closing (:mod:`hsqbench.planner.grasp`).

Network (cgn-pytorch 0.4.3, ``CGN.build_6d_grasps``): a grasp is a 4x4 pose ``T`` of the gripper
*base* with ``T[:3, 0]`` the closing direction ``x``, ``T[:3, 2]`` the approach ``z`` and
``T[:3, 1] = z x x``; for a predicted contact point ``c`` and width ``w`` its origin is
``c + (w / 2) x - depth z`` with ``depth = 0.1034 m``. The fingertip centre, midway between the
two fingers at the contacts' depth, is therefore ``T[:3, 3] + depth z``, and that is ``P_G``; the
rotation is ``T[:3, :3]`` itself (same column order and handedness).

Input frames: the cgn-pytorch weights were trained on clouds in the scene's world frame (z up)
centred on their mean (its ``dataset.py``; its README says the same), the original TensorFlow
release on one camera's optical frame (x right, y down, z forward). Both are offered
(:func:`world_centred_frame`, :func:`look_at_frame`); a frame is a 4x4 ``T_world_frame``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

Array = NDArray[np.float64]


def world_centred_frame(points: Array) -> Array:
    """``T_world_frame``: world axes, origin at the cloud's mean."""
    frame = np.eye(4)
    frame[:3, 3] = points.mean(axis=0)
    return frame


def look_at_frame(camera: Array, target: Array, up: Array) -> Array:
    """``T_world_frame`` of a virtual camera at ``camera`` aimed at ``target``: optical axes
    (x right, y down, z forward), no roll (image "down" is ``-up`` seen from the camera).

    Raises:
        ValueError: the camera sits on the target, or looks straight along ``up``.
    """
    z = np.asarray(target, float) - np.asarray(camera, float)
    dist = float(np.linalg.norm(z))
    if dist < 1e-9:
        raise ValueError("a camera cannot look at a target at its own position")
    z /= dist
    down = -np.asarray(up, float)
    y = down - np.dot(down, z) * z
    norm = float(np.linalg.norm(y))
    if norm < 1e-6:
        raise ValueError("the camera looks along the up axis: its roll is undefined")
    y /= norm
    frame = np.eye(4)
    frame[:3, :3] = np.column_stack([np.cross(y, z), y, z])
    frame[:3, 3] = camera
    return frame


def to_frame(points: Array, frame: Array) -> Array:
    """World points (N, 3) expressed in ``frame`` (``T_world_frame``)."""
    return (points - frame[:3, 3]) @ frame[:3, :3]


def poses_to_world(poses: Array, frame: Array) -> Array:
    """(G, 4, 4) poses given in ``frame`` as world poses."""
    return np.einsum("ij,gjk->gik", frame, poses)


def network_to_grasp_frames(poses: Array, depth_m: float) -> tuple[Array, Array]:
    """Network base poses (G, 4, 4) -> (``P_G`` (G, 3), rotations (G, 3, 3), columns closing,
    third, approach), in the poses' frame. Rotations are re-orthonormalised in float64 (the
    network computes in float32)."""
    poses = np.asarray(poses, dtype=np.float64)
    rot = poses[:, :3, :3]
    closing = rot[:, :, 0] / np.linalg.norm(rot[:, :, 0], axis=1, keepdims=True)
    approach = rot[:, :, 2] - np.einsum("gi,gi->g", rot[:, :, 2], closing)[:, None] * closing
    approach /= np.linalg.norm(approach, axis=1, keepdims=True)
    third = np.cross(approach, closing)
    rotations = np.stack([closing, third, approach], axis=-1)
    return poses[:, :3, 3] + depth_m * approach, rotations


def grasp_frames_to_network(positions: Array, rotations: Array, depth_m: float) -> Array:
    """Inverse of :func:`network_to_grasp_frames`: (G, 4, 4) gripper-base poses."""
    poses = np.tile(np.eye(4), (positions.shape[0], 1, 1))
    poses[:, :3, :3] = rotations
    poses[:, :3, 3] = positions - depth_m * rotations[:, :, 2]
    return poses


def table_patch(centre: Array, plane: Array, radius_m: float, spacing_m: float) -> Array:
    """Grid points of the support plane (unit normal) within ``radius_m`` of ``centre``'s
    projection on it: the table the network saw in training, which the harness crops away."""
    normal = plane[:3]
    foot = centre - (np.dot(normal, centre) + plane[3]) * normal
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(normal, helper)
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    ticks = np.arange(-radius_m, radius_m + 0.5 * spacing_m, spacing_m)
    a, b = np.meshgrid(ticks, ticks, indexing="ij")
    keep = a**2 + b**2 <= radius_m**2
    return foot + a[keep, None] * u + b[keep, None] * v


def visible_from(points: Array, camera: Array, radius_factor: float = 1e4) -> NDArray[np.bool_]:
    """Points a camera at ``camera`` sees (hidden point removal, Katz, Tal and Basri 2007).

    Each point is flipped about a sphere around the camera (radius ``radius_factor`` times the
    farthest point); the points on the convex hull of the flipped cloud and the camera are the
    visible ones. Used to split a fused cloud into views when the cameras' own parts are unknown.
    ``radius_factor`` 1e4: on the harness's noisy clouds smaller spheres keep only the outermost
    points (mustard bottle: 1 % of a camera's points at 10, 22 % at 100, 98 % at 1e4).
    """
    rel = points - camera
    norm = np.linalg.norm(rel, axis=1, keepdims=True)
    norm = np.maximum(norm, 1e-12)
    radius = radius_factor * float(norm.max())
    flipped = rel + 2.0 * (radius - norm) * rel / norm
    hull = ConvexHull(np.vstack([flipped, np.zeros((1, 3))]))
    mask = np.zeros(points.shape[0] + 1, dtype=bool)
    mask[hull.vertices] = True
    return mask[:-1]


def seen_in_image(points: Array, view: Any, tolerance_m: float) -> NDArray[np.bool_]:
    """Points (N, 3) that a depth image measured: those projecting into the image (nearest
    pixel) within ``tolerance_m`` of the planar depth there (``view``: ``depth_m``, ``K``,
    ``T_world_camera`` as in :class:`~hsqbench.sim.perceived.CameraView`)."""
    depth = np.asarray(view.depth_m, dtype=np.float64)
    K = np.asarray(view.K, dtype=np.float64)
    T = np.asarray(view.T_world_camera, dtype=np.float64)
    cam = (points - T[:3, 3]) @ T[:3, :3]
    z = cam[:, 2]
    seen = np.zeros(len(points), dtype=bool)
    front = np.flatnonzero(z > 1e-9)
    u = np.rint(K[0, 0] * cam[front, 0] / z[front] + K[0, 2]).astype(np.int64)
    v = np.rint(K[1, 1] * cam[front, 1] / z[front] + K[1, 2]).astype(np.int64)
    inside = (u >= 0) & (u < depth.shape[1]) & (v >= 0) & (v < depth.shape[0])
    rows = front[inside]
    d = depth[v[inside], u[inside]]
    seen[rows] = (d > 0) & (np.abs(d - z[rows]) <= tolerance_m)
    return seen
