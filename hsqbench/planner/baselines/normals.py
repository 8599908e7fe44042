"""Surface normals of a point cloud: batched PCA over k-nearest neighbourhoods, oriented outward.

- Estimation: the normal at a point is the eigenvector of the smallest eigenvalue of the
  covariance of its ``k`` nearest neighbours (the point included). The ratio
  ``lambda_min / (lambda_0 + lambda_1 + lambda_2)`` (the *surface variation*, 0 on a plane, 1/3
  for an isotropic blob) says how planar the neighbourhood is.
- Orientation: PCA gives a line, not a direction. A fused cloud from cameras on opposite sides
  cannot be oriented by viewpoint without knowing which camera saw each point, so each normal is
  pointed away from the centroid of the cloud within ``radius`` of its point: on a convex surface
  every other point lies behind the tangent plane, so that centroid lies inside the object.
  The rule fails in concavities (the inside of a bowl) and where a neighbouring object dominates
  the neighbourhood (packed scenes); the neighbourhood centroid is computed on a coarse voxel
  grid so the cost is ``O(points x coarse voxels)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from hsqbench.planner.downsample import voxel_downsample

Array = NDArray[np.float64]

#: Points per block when comparing every point with every coarse voxel (memory bound).
_CHUNK_PAIRS = 2_000_000


def pair_dots(a: Array, b: Array) -> Array:
    """(n, m) dot products of the rows of ``a`` (n, 3) and ``b`` (m, 3), as broadcast sums:
    ``a @ b.T`` is too skinny for BLAS, whose threads only add overhead on a busy machine."""
    return a[:, 0, None] * b[:, 0] + a[:, 1, None] * b[:, 1] + a[:, 2, None] * b[:, 2]


@dataclass(frozen=True)
class Normals:
    """Unit normals of a cloud and the planarity of each neighbourhood.

    Attributes:
        normals: (N, 3) unit normals (outward after :func:`orient_outward`).
        variation: (N,) surface variation ``lambda_min / sum(lambda)`` in [0, 1/3].
    """

    normals: Array
    variation: Array


def estimate_normals(points: Array, k: int) -> Normals:
    """PCA normals over the ``k`` nearest neighbours of every point (unoriented).

    Raises:
        ValueError: ``k`` < 3 or the cloud has fewer than ``k`` points.
    """
    points = np.asarray(points, dtype=np.float64)
    n = points.shape[0]
    if k < 3:
        raise ValueError(f"normal estimation needs k >= 3 neighbours (a plane), got {k}")
    if n < k:
        raise ValueError(
            f"normal estimation with k = {k} neighbours needs at least {k} points, got {n}"
        )
    _, idx = cKDTree(points).query(points, k=k)
    nb = points[idx]
    centred = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", centred, centred) / k
    values, vectors = np.linalg.eigh(cov)
    total = np.maximum(values.sum(axis=1), 1e-300)
    return Normals(vectors[:, :, 0], np.clip(values[:, 0], 0.0, None) / total)


def neighbourhood_centroids(points: Array, radius_m: float, voxel_m: float) -> Array:
    """(N, 3) centroid of the cloud within ``radius_m`` of each point, from ``voxel_m`` voxels.

    Each voxel's centroid stands for its points (weighted by their count); a point's own voxel
    is always within reach, so every row is defined.
    """
    coarse = voxel_downsample(points, voxel_m)
    centres, weights = coarse.points, coarse.counts
    out = np.empty_like(points)
    r2 = radius_m * radius_m
    c2 = np.einsum("ij,ij->i", centres, centres)
    block = max(1, _CHUNK_PAIRS // max(len(centres), 1))
    for start in range(0, points.shape[0], block):
        p = points[start : start + block]
        d2 = np.einsum("ij,ij->i", p, p)[:, None] - 2.0 * pair_dots(p, centres) + c2[None, :]
        w = np.where(d2 <= r2, weights[None, :], 0.0)
        # The point's own voxel may lie just outside the radius (voxel >> radius is a misuse).
        w[np.arange(len(p)), coarse.inverse[start : start + block]] = weights[
            coarse.inverse[start : start + block]
        ]
        # einsum's own loop, not BLAS (see pair_dots).
        total = np.einsum("ij,jk->ik", w, centres)
        out[start : start + block] = total / w.sum(axis=1, keepdims=True)
    return out


def orient_outward(points: Array, normals: Array, radius_m: float, voxel_m: float) -> Array:
    """Flip each normal to point away from its neighbourhood centroid (see the module notes)."""
    inward = neighbourhood_centroids(points, radius_m, voxel_m) - points
    sign = np.where(np.einsum("ij,ij->i", normals, inward) > 0.0, -1.0, 1.0)
    return normals * sign[:, None]
