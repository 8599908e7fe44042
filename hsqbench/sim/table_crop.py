"""Workspace crop, table removal and fusion of the cameras' points (steps 4 and 5 of
:mod:`hsqbench.sim.perception`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.sim.perception_config import CropConfig

Array = NDArray[np.float64]


def fit_plane(points: Array, up: Array) -> Array:
    """Least-squares plane (4,) through (N, 3) points (smallest-variance direction of their
    covariance), normal oriented along ``up``."""
    centre = points.mean(axis=0)
    q = points - centre
    _, vecs = np.linalg.eigh(np.einsum("ni,nj->ij", q, q))
    n = vecs[:, 0] if vecs[:, 0] @ up >= 0 else -vecs[:, 0]
    return np.array([*n, -n @ centre])


def refit_table_plane(points: Array, nominal: Array, crop: CropConfig) -> Array:
    """The table plane as seen in ``points`` (one camera's points over the workspace).

    Points within ``refit_band_m`` of the nominal plane are fitted, then refitted twice on the
    points within ``refit_inlier_m`` of the previous fit (this drops the object points in the
    band). Falls back to ``nominal`` when too few points support the fit or the fit tilts more
    than ``refit_max_tilt_deg`` from it.
    """
    band = np.abs(points @ nominal[:3] + nominal[3]) < crop.refit_band_m
    if band.sum() < crop.refit_min_points:
        return nominal
    sample = points[band]
    plane = fit_plane(sample, nominal[:3])
    for _ in range(2):
        inliers = np.abs(sample @ plane[:3] + plane[3]) < crop.refit_inlier_m
        if inliers.sum() < crop.refit_min_points:
            return nominal
        plane = fit_plane(sample[inliers], nominal[:3])
    tilt = np.rad2deg(np.arccos(np.clip(plane[:3] @ nominal[:3], -1.0, 1.0)))
    return plane if tilt <= crop.refit_max_tilt_deg else nominal


def workspace_mask(points: Array, lo: Array, hi: Array, margin_m: float) -> NDArray[np.bool_]:
    """Points inside the box ``[lo, hi]`` grown by ``margin_m`` on every side, without a bottom:
    below the box is the table, removed by its plane (points just under the nominal table top
    are needed to re-fit it)."""
    inside = np.all(points[:, :2] >= lo[:2] - margin_m, axis=1)
    return inside & np.all(points <= hi + margin_m, axis=1)


def fuse_and_downsample(clouds: Sequence[Array], voxel_m: float) -> tuple[Array, NDArray[np.int64]]:
    """Voxel centroids of the union of ``clouds`` and, per voxel, the index of the cloud that
    contributed most of its points (ties go to the lower index)."""
    counts = [len(c) for c in clouds]
    if sum(counts) == 0:
        return np.zeros((0, 3)), np.zeros(0, dtype=np.int64)
    points = np.concatenate([c for c in clouds if len(c)])
    source = np.repeat(np.arange(len(clouds)), counts)
    down = voxel_downsample(points, voxel_m)
    per = np.bincount(
        down.inverse * len(clouds) + source, minlength=len(down.points) * len(clouds)
    ).reshape(len(down.points), len(clouds))
    return down.points, np.argmax(per, axis=1).astype(np.int64)
