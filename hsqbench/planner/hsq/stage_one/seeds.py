"""Starting superquadrics for stage one: the paper's K rule, K-means parts, inertia ellipsoids.

Inertia ellipsoid. Treat a part as unit point masses with covariance ``C = V diag(l) V^T``
(``l`` in m²). Its inertia about principal axis i, per unit mass, is ``l_j + l_k``. A solid ellipsoid
of the same mass with semi-axes ``a`` along ``V`` has ``(a_j² + a_k²) / 5``. Asking the ellipsoid
for half the part's inertia about every axis,

    (a_j² + a_k²) / 5 = (l_j + l_k) / 2        for the three (i, j, k),

and summing the three equations gives ``sum a² = 5/2 sum l``, hence ``a_i = sqrt(5 l_i / 2)``:
each semi-axis is ``1/sqrt(2)`` of the ellipsoid that matches the part's second moments, so the
seed starts inside the part and grows.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import NDArray
from sklearn.cluster import KMeans
from threadpoolctl import ThreadpoolController

from hsqbench.planner.hsq.stage_one.radial import SQState

Array = NDArray[np.float64]


def paper_k(count: int) -> int:
    """K of the paper: 6 below 8000 points, then 8 plus 2 for every further 4000 points."""
    if count < 8000:
        return 6
    return 8 + 2 * ((count - 8000) // 4000)


def inertia_ellipsoid(points: Array, scale_min_m: float, scale_max_m: float) -> SQState:
    """The ellipsoid (eps1 = eps2 = 1) with half the moment of inertia of ``points`` (module doc).

    Semi-axes are clipped to ``[scale_min_m, scale_max_m]``; the longest is the local z axis.
    """
    centre = points.mean(axis=0)
    cov = np.cov(points - centre, rowvar=False, bias=True) if len(points) > 1 else np.zeros((3, 3))
    var, axes = np.linalg.eigh(cov)
    if np.linalg.det(axes) < 0.0:
        axes[:, 0] = -axes[:, 0]
    scale = np.clip(np.sqrt(2.5 * np.maximum(var, 0.0)), scale_min_m, scale_max_m)
    return SQState(1.0, 1.0, scale, axes, centre)


@cache
def _thread_pools() -> ThreadpoolController:
    """The process's BLAS and OpenMP pools, looked up once (a lookup costs about 2 ms)."""
    return ThreadpoolController()


def kmeans_labels(points: Array, k: int, seed: int, n_init: int) -> NDArray[np.int64]:
    """K-means labels (N,) with a fixed seed; ``k`` is capped by the number of distinct points.

    Runs on one thread: on a small cloud OpenMP start-up costs more than it saves (measured 10 to
    1500 ms with two busy threads against 10 to 20 ms with one), and one thread keeps the result
    independent of the machine.
    """
    k = min(k, len(np.unique(points, axis=0)))
    if k <= 1:
        return np.zeros(len(points), dtype=np.int64)
    km = KMeans(n_clusters=k, n_init=n_init, random_state=seed)
    with _thread_pools().limit(limits=1):
        return km.fit_predict(points).astype(np.int64)
