"""A depth image seen again from a virtual camera: the harness's depth re-projected into the
camera pose the volumetric networks were trained with (``volumetric.viewpoint: training``).

Every measured pixel of the source image becomes a point (its ray times its planar depth), the
points are projected into the virtual pinhole camera and each writes its depth to the
``splat_px`` neighbourhood of its pixel, the nearest depth winning (a z-buffer): the virtual
pixels are finer than the source's at the object, and one source point must leave no hole
between its neighbours. Surfaces the real camera did not see stay empty (depth 0, no
measurement), never invented.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.learned.frames import look_at_frame

Array = NDArray[np.float64]


@dataclass(frozen=True)
class VirtualView:
    """A depth image and its camera (the fields :func:`tsdf.integrate` reads)."""

    depth_m: NDArray[np.float32]
    K: Array
    T_world_camera: Array


def camera_on_sphere(
    target: Array, distance_m: float, polar_deg: float, azimuth_deg: float
) -> Array:
    """``T_world_camera`` (optical axes) of a camera ``distance_m`` from ``target`` at
    ``polar_deg`` from the vertical and ``azimuth_deg`` about it, looking at ``target`` without
    roll (VGN's ``camera_on_sphere``)."""
    theta, phi = np.deg2rad(polar_deg), np.deg2rad(azimuth_deg)
    eye = target + distance_m * np.array(
        [np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]
    )
    return look_at_frame(eye, target, np.array([0.0, 0.0, 1.0]))


def reproject(
    view: Any, T_world_virtual: Array, K: Array, size_px: tuple[int, int], splat_px: int
) -> VirtualView:
    """``view`` (``depth_m``, ``K``, ``T_world_camera``) as the camera ``T_world_virtual`` with
    intrinsics ``K`` and ``size_px`` (width, height) would measure it (module notes)."""
    depth = np.asarray(view.depth_m, dtype=np.float64)
    Ks = np.asarray(view.K, dtype=np.float64)
    T = np.asarray(view.T_world_camera, dtype=np.float64)
    v, u = np.nonzero(depth > 0)
    d = depth[v, u]
    rays = np.column_stack([(u - Ks[0, 2]) / Ks[0, 0], (v - Ks[1, 2]) / Ks[1, 1], np.ones(len(d))])
    world = (rays * d[:, None]) @ T[:3, :3].T + T[:3, 3]
    cam = (world - T_world_virtual[:3, 3]) @ T_world_virtual[:3, :3]
    front = cam[:, 2] > 1e-6
    cam = cam[front]
    pu = np.rint(K[0, 0] * cam[:, 0] / cam[:, 2] + K[0, 2]).astype(np.int64)
    pv = np.rint(K[1, 1] * cam[:, 1] / cam[:, 2] + K[1, 2]).astype(np.int64)
    width, height = size_px
    out = np.full(height * width, np.inf)
    for du in range(-splat_px, splat_px + 1):
        for dv in range(-splat_px, splat_px + 1):
            uu, vv = pu + du, pv + dv
            ok = (uu >= 0) & (uu < width) & (vv >= 0) & (vv < height)
            np.minimum.at(out, vv[ok] * width + uu[ok], cam[ok, 2])
    out = np.where(np.isfinite(out), out, 0.0).reshape(height, width)
    return VirtualView(
        depth_m=out.astype(np.float32),
        K=np.asarray(K, dtype=np.float64),
        T_world_camera=T_world_virtual,
    )
