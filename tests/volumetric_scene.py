"""Exact depth images of axis-aligned boxes on a table, for the vgn and giga planners' tests:
each pixel's ray intersected with the table plane z = 0 and the boxes (slab method)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.learned.frames import look_at_frame

#: The harness's two depth cameras (scenes/cameras.xml) and the point they look at.
CAMERAS = np.array([[0.62, 0.78, 0.55], [0.62, -0.78, 0.55]])
TARGET = np.array([0.5, 0.0, 0.0])
TABLE = (0.0, 0.0, 1.0, 0.0)
#: A 5 x 8 x 8 cm box: across y (5 cm) it fits the 7 cm width limit, across x (8 cm) it does not.
BOX = (np.array([0.46, -0.025, 0.0]), np.array([0.54, 0.025, 0.08]))


def planner_or_skip(name: str):
    """The registered planner ``name`` (vgn or giga), or the test skipped when the published
    weights or torch are not here."""
    import pytest

    from hsqbench.planner.learned import volumetric, weights
    from hsqbench.planner.registry import get_planner

    try:
        for training in ("packed", "pile"):
            weights.weights_path(name, training, "unused", download=False)
    except weights.WeightsError as exc:
        pytest.skip(f"the published weights are not here ({exc}); set HSQ_MODELS_DIR")
    if not volumetric.available():
        pytest.skip("torch is not installed (the optional 'learned' extra)")
    return get_planner(name)


@dataclass(frozen=True)
class DepthView:
    """What the planners read of a camera (the fields of ``CameraView`` they use)."""

    depth_m: NDArray[np.float32]
    K: NDArray[np.float64]
    T_world_camera: NDArray[np.float64]


def intrinsics(width: int = 320, height: int = 288, fovy_deg: float = 65.0) -> NDArray:
    """Half the harness cameras' resolution (640 x 576), same field of view."""
    f = 0.5 * height / np.tan(0.5 * np.deg2rad(fovy_deg))
    return np.array([[f, 0, 0.5 * (width - 1)], [0, f, 0.5 * (height - 1)], [0, 0, 1.0]])


def render(
    camera: NDArray,
    boxes: list[tuple[NDArray, NDArray]],
    K: NDArray | None = None,
    size: tuple[int, int] = (320, 288),
) -> DepthView:
    """Planar depth of the table (z = 0) and the boxes ``(lower, upper)`` seen from ``camera``
    aimed at :data:`TARGET`."""
    K = intrinsics(*size) if K is None else K
    T = look_at_frame(np.asarray(camera, float), TARGET, np.array([0.0, 0.0, 1.0]))
    u, v = np.meshgrid(np.arange(size[0]), np.arange(size[1]))
    rays_cam = np.stack(
        [(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(u.shape)], axis=-1
    )
    rays = rays_cam @ T[:3, :3].T  # planar depth s: point = camera + s * ray
    origin = T[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(rays[..., 2] < 0, -origin[2] / rays[..., 2], np.inf)
        for lower, upper in boxes:
            t0 = (np.asarray(lower) - origin) / rays
            t1 = (np.asarray(upper) - origin) / rays
            near = np.nanmax(np.minimum(t0, t1), axis=-1)
            far = np.nanmin(np.maximum(t0, t1), axis=-1)
            hit = (near <= far) & (near > 0)
            depth = np.where(hit, np.minimum(depth, near), depth)
    depth = np.where(np.isfinite(depth), depth, 0.0)
    return DepthView(depth_m=depth.astype(np.float32), K=K, T_world_camera=T)


def box_scene(boxes: list[tuple[NDArray, NDArray]]) -> tuple[DepthView, ...]:
    """Both harness cameras' views of ``boxes`` on the table."""
    return tuple(render(c, boxes) for c in CAMERAS)


def box_cloud(boxes: list[tuple[NDArray, NDArray]], spacing_m: float = 0.004) -> NDArray:
    """A grid of points on the boxes' top faces: the cloud only places the planners' cubes."""
    pts = []
    for lower, upper in boxes:
        xs = np.arange(lower[0], upper[0] + 1e-9, spacing_m)
        ys = np.arange(lower[1], upper[1] + 1e-9, spacing_m)
        gx, gy = np.meshgrid(xs, ys, indexing="ij")
        pts.append(np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, upper[2])]))
    return np.concatenate(pts)
