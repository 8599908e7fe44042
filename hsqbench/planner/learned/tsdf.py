"""A truncated signed distance field fused from depth images, on the grid VGN and GIGA read.

Pure numpy (no open3d): the integration of Open3D's ``UniformTSDFVolume``, which VGN and GIGA
use, written out. Every voxel centre is projected into each depth image (nearest pixel); where
the pixel has a depth ``d`` and the voxel lies at optical depth ``z``, the signed distance along
the pixel's ray is ``(d - z) * sqrt(1 + ((u - cx) / fx)^2 + ((v - cy) / fy)^2)``. Voxels more
than the truncation behind the surface are left alone; the others average
``min(1, sdf / truncation)`` over the images (weight 1 each).

The networks' input (:meth:`TSDFGrid.network_input`) is what VGN's ``get_grid`` reads out of
Open3D: ``(tsdf + 1) / 2`` at observed voxels with ``-0.98 <= tsdf < 0.98``, 0 elsewhere (free
space far from a surface, space never seen, deep inside an object). So 0.5 is the surface,
above it free space, below it the inside.

Grid frame: world axes, origin at the grid's lower corner ``origin``; voxel ``(i, j, k)`` has its
centre at ``origin + (ijk + 0.5) * voxel_m``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Open3D's read-out keeps voxels with ``-0.98 <= tsdf < 0.98`` (the rest are "far").
NEAR_SURFACE_TSDF = 0.98


@dataclass(frozen=True)
class TSDFGrid:
    """A fused TSDF on an axis-aligned grid.

    Attributes:
        tsdf: (X, Y, Z) float32 truncated signed distance over the truncation, in [-1, 1];
            1 where no image saw the voxel.
        weight: (X, Y, Z) float32 number of images that updated each voxel.
        origin: (3,) world position of the grid's lower corner, metres.
        voxel_m: edge of one voxel, metres.
    """

    tsdf: NDArray[np.float32]
    weight: NDArray[np.float32]
    origin: Array
    voxel_m: float

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(int(n) for n in self.tsdf.shape)  # type: ignore[return-value]

    def network_input(self) -> NDArray[np.float32]:
        """(X, Y, Z) float32: ``(tsdf + 1) / 2`` near surfaces, 0 elsewhere (module notes)."""
        near = (
            (self.weight > 0) & (self.tsdf < NEAR_SURFACE_TSDF) & (self.tsdf >= -NEAR_SURFACE_TSDF)
        )
        return np.where(near, 0.5 * (self.tsdf + 1.0), 0.0).astype(np.float32)

    def surface_points(self) -> Array:
        """(N, 3) world points where the TSDF changes sign between two observed neighbours
        (linear interpolation along the grid axes): the fused surface, for display and tests."""
        seen = self.weight > 0
        found = []
        for axis in range(3):
            a = np.moveaxis(self.tsdf, axis, 0).astype(np.float64)
            ok = np.moveaxis(seen, axis, 0)
            lo, hi = a[:-1], a[1:]
            # A sign change between truncated values (|tsdf| < 1 on both sides) is a surface;
            # one between +1 (far free space) and -1 would be an unobserved jump.
            cross = ok[:-1] & ok[1:] & (lo * hi < 0) & (np.abs(lo) < 1) & (np.abs(hi) < 1)
            idx = np.argwhere(cross).astype(np.float64)
            t = lo[cross] / (lo[cross] - hi[cross])
            idx[:, 0] += t
            order = [axis, *(a for a in range(3) if a != axis)]  # moveaxis's axis order
            found.append(idx[:, np.argsort(order)])
        ijk = np.concatenate(found) if found else np.zeros((0, 3))
        return self.origin + (ijk + 0.5) * self.voxel_m

    def voxel_centres(self) -> Array:
        """(X * Y * Z, 3) world centres in C order of the grid."""
        return voxel_centres(self.origin, self.voxel_m, self.shape)


def voxel_centres(origin: Array, voxel_m: float, shape: Sequence[int]) -> Array:
    """(X * Y * Z, 3) world centres of a grid's voxels, C order."""
    axes = [np.arange(n, dtype=np.float64) for n in shape]
    ijk = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return np.asarray(origin, dtype=np.float64) + (ijk + 0.5) * voxel_m


def integrate(
    views: Sequence[Any],
    origin: Array,
    voxel_m: float,
    shape: Sequence[int],
    truncation_m: float,
) -> TSDFGrid:
    """Fuse depth images into a TSDF on the grid ``origin``, ``voxel_m``, ``shape``.

    Args:
        views: objects with ``depth_m`` (H, W) planar depth in metres (0: no measurement),
            ``K`` (3, 3) intrinsics with pixel centres at integer coordinates and
            ``T_world_camera`` (4, 4) optical-frame pose (x right, y down, z forward); the
            harness's :class:`~hsqbench.sim.perceived.CameraView`.
        origin: (3,) lower corner of the grid, world metres.
        voxel_m: voxel edge, metres.
        shape: voxels along x, y, z.
        truncation_m: the truncation distance, metres.

    Raises:
        ValueError: no view, a bad grid, or a view whose arrays have the wrong shape.
    """
    if not views:
        raise ValueError("a TSDF needs at least one depth image")
    if not (voxel_m > 0 and truncation_m > 0) or len(shape) != 3 or min(shape) < 1:
        raise ValueError(
            f"a TSDF grid needs voxel_m > 0, truncation_m > 0 and three positive sizes, got "
            f"{voxel_m}, {truncation_m}, {tuple(shape)}"
        )
    centres = voxel_centres(origin, voxel_m, shape)
    total = np.zeros(len(centres))
    weight = np.zeros(len(centres))
    for view in views:
        sdf = _view_sdf(view, centres)
        update = np.isfinite(sdf) & (sdf > -truncation_m)
        total[update] += np.minimum(1.0, sdf[update] / truncation_m)
        weight[update] += 1.0
    tsdf = np.where(weight > 0, total / np.maximum(weight, 1.0), 1.0)
    return TSDFGrid(
        tsdf=tsdf.reshape(tuple(shape)).astype(np.float32),
        weight=weight.reshape(tuple(shape)).astype(np.float32),
        origin=np.asarray(origin, dtype=np.float64).copy(),
        voxel_m=float(voxel_m),
    )


def _view_sdf(view: Any, centres: Array) -> Array:
    """Signed distance along each centre's pixel ray to the surface one image sees (NaN where
    the image says nothing: behind the camera, outside the image, no depth)."""
    depth = np.asarray(view.depth_m, dtype=np.float64)
    K = np.asarray(view.K, dtype=np.float64)
    T = np.asarray(view.T_world_camera, dtype=np.float64)
    if depth.ndim != 2 or K.shape != (3, 3) or T.shape != (4, 4):
        raise ValueError(
            "a depth view needs depth_m (H, W), K (3, 3) and T_world_camera (4, 4); got "
            f"{depth.shape}, {K.shape}, {T.shape}"
        )
    cam = (centres - T[:3, 3]) @ T[:3, :3]
    z = cam[:, 2]
    sdf = np.full(len(centres), np.nan)
    front = z > 1e-9
    u = np.rint(K[0, 0] * cam[front, 0] / z[front] + K[0, 2])
    v = np.rint(K[1, 1] * cam[front, 1] / z[front] + K[1, 2])
    height, width = depth.shape
    inside = (u >= 0) & (u < width) & (v >= 0) & (v < height)
    rows = np.flatnonzero(front)[inside]
    ui, vi = u[inside].astype(np.int64), v[inside].astype(np.int64)
    d = depth[vi, ui]
    ray = np.sqrt(1.0 + ((ui - K[0, 2]) / K[0, 0]) ** 2 + ((vi - K[1, 2]) / K[1, 1]) ** 2)
    measured = d > 0
    sdf[rows[measured]] = (d[measured] - z[rows[measured]]) * ray[measured]
    return sdf
