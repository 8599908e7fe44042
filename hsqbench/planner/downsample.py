"""Voxel-grid downsampling with a map back to the input points.

Each occupied voxel of an axis-aligned grid (cells of ``voxel_m`` metres, anchored at the cloud's
minimum corner) is replaced by the centroid of its points. The centroid averages the sensor noise
of the points it replaces; ``inverse[i]`` names the voxel of input point ``i``, so any per-voxel
result (an inlier posterior) maps back to every input point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

#: Each round of growing the voxel aims this far below the point budget, so that one or two
#: rounds suffice (the count of a surface falls roughly with the square of the voxel size).
_GROW_MARGIN = 0.9


@dataclass(frozen=True)
class Downsampled:
    """A downsampled cloud.

    Attributes:
        points: (M, 3) voxel centroids, metres.
        counts: (M,) number of input points in each voxel.
        inverse: (N,) index into ``points`` of each input point's voxel.
        voxel_m: the voxel size that was used, metres.
    """

    points: Array
    counts: Array
    inverse: NDArray[np.int64]
    voxel_m: float


def voxel_keys(points: Array, voxel_m: float) -> NDArray[np.int64]:
    """One integer per occupied voxel (dense labels 0..M-1), per point (N,)."""
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    cells = np.floor((points - points.min(axis=0)) / voxel_m).astype(np.int64)
    dims = cells.max(axis=0) + 1
    if float(np.prod(dims.astype(np.float64))) < 2.0**62:
        flat = cells[:, 0] + dims[0] * (cells[:, 1] + dims[1] * cells[:, 2])
        _, inverse = np.unique(flat, return_inverse=True)
    else:
        _, inverse = np.unique(cells, axis=0, return_inverse=True)
    return inverse.ravel().astype(np.int64)


def count_voxels(points: Array, voxel_m: float) -> int:
    """Number of occupied voxels of size ``voxel_m``."""
    keys = voxel_keys(points, voxel_m)
    return int(keys.max()) + 1 if len(keys) else 0


def voxel_downsample(points: Array, voxel_m: float) -> Downsampled:
    """Centroid of each occupied voxel."""
    if not voxel_m > 0.0:
        raise ValueError(f"voxel size must be positive metres, got {voxel_m}")
    inverse = voxel_keys(points, voxel_m)
    m = int(inverse.max()) + 1 if len(inverse) else 0
    counts = np.bincount(inverse, minlength=m).astype(np.float64)
    centroids = np.column_stack(
        [np.bincount(inverse, weights=points[:, k], minlength=m) for k in range(3)]
    )
    return Downsampled(centroids / counts[:, None], counts, inverse, float(voxel_m))


def downsample_to_budget(points: Array, voxel_m: float, max_points: int) -> Downsampled:
    """Downsample at ``voxel_m``; grow the voxel until at most ``max_points`` centroids remain."""
    down = voxel_downsample(points, voxel_m)
    while len(down.points) > max_points:
        grow = max(np.sqrt(len(down.points) / (_GROW_MARGIN * max_points)), 1.1)
        down = voxel_downsample(points, down.voxel_m * grow)
    return down
