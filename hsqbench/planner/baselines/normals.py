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
  the neighbourhood (packed scenes). The neighbourhood centroid is computed on a coarse voxel
  grid: its cost follows the number of coarse voxels within the radius of each point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from hsqbench.planner.downsample import voxel_downsample

Array = NDArray[np.float64]


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

    Each voxel's centroid stands for its points (weighted by their count). A point and its own
    voxel's centroid share a cube of side ``voxel_m``, so with ``voxel_m * sqrt(3) <= radius_m``
    every point has at least that neighbour.

    Raises:
        ValueError: ``voxel_m * sqrt(3) > radius_m``.
    """
    if voxel_m * np.sqrt(3.0) > radius_m:
        raise ValueError(
            f"the orientation voxel ({voxel_m:g} m) must be at most radius / sqrt(3) "
            f"({radius_m / np.sqrt(3.0):.4g} m) so that each point reaches its own voxel"
        )
    coarse = voxel_downsample(points, voxel_m)
    centres, weights = coarse.points, coarse.counts
    pairs = cKDTree(points).sparse_distance_matrix(
        cKDTree(centres), radius_m, output_type="ndarray"
    )
    i, w = pairs["i"], weights[pairs["j"]]
    n = points.shape[0]
    total = np.column_stack(
        [np.bincount(i, weights=w * centres[pairs["j"], k], minlength=n) for k in range(3)]
    )
    return total / np.bincount(i, weights=w, minlength=n)[:, None]


def orient_outward(points: Array, normals: Array, radius_m: float, voxel_m: float) -> Array:
    """Flip each normal to point away from its neighbourhood centroid (see the module notes)."""
    inward = neighbourhood_centroids(points, radius_m, voxel_m) - points
    sign = np.where(np.einsum("ij,ij->i", normals, inward) > 0.0, -1.0, 1.0)
    return normals * sign[:, None]
