"""Stage one of the paper: superquadrics fitted to a noisy point cloud, alone or as hidden parts.

Inference is EM with switching (EMS, Liu et al. CVPR 2022) on the paper's mixture model (every
point an outlier uniform over the workspace volume, or an inlier Gaussian around the surface);
the paper itself samples the same model with the optimisation-based Gibbs sampler of Wu et al.
(ECCV 2022). The formulas, the residual and the switching moves are in :mod:`.ems` and
:mod:`.radial`.

- :func:`fit_superquadric`: one superquadric for the whole cloud, low outlier weight (the
  single-superquadric baseline).
- :func:`recover_hidden_superquadrics`: the paper's K + 1 seeds (K-means parts with the paper's
  rule for K, plus the whole cloud), each started as the ellipsoid with half its part's moment of
  inertia (:mod:`.seeds`) and fitted with a high outlier weight, so it grows into a local part.

Both voxel-downsample the cloud first (:mod:`.downsample`) and map results back to the caller's
points: a point takes the inlier posterior of its voxel's centroid, the point the model was fitted
to, so ``inliers`` and ``inlier_probability`` index the input array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.config import RecoveryConfig
from hsqbench.planner.downsample import Downsampled, count_voxels, downsample_to_budget
from hsqbench.planner.ems import EMSResult, MixtureModel, ems_fit
from hsqbench.planner.radial import SQState, radial_residual
from hsqbench.planner.seeds import inertia_ellipsoid, kmeans_labels, paper_k
from hsqbench.superquadric import N_PARAMS, Superquadric, alpha_beta, as_points

Array = NDArray[np.float64]


@dataclass(frozen=True)
class FitResult:
    """One superquadric fitted to a whole cloud.

    Attributes:
        superquadric: the fitted superquadric (metres, world frame).
        inlier_probability: (N,) posterior probability that each input point is an inlier.
        sigma_m: fitted noise std of the inliers' radial distances, metres (on voxel centroids).
        cost: final negative log-likelihood of the mixture per voxel centroid, nats.
        iterations: EM iterations run, switching trials included.
        switches: how many times switching replaced the solution.
    """

    superquadric: Superquadric
    inlier_probability: Array
    sigma_m: float
    cost: float
    iterations: int
    switches: int


@dataclass(frozen=True)
class HiddenSuperquadric:
    """One hidden superquadric: a part of the cloud that a superquadric describes well.

    Attributes:
        superquadric: the fitted superquadric (metres, world frame).
        inliers: int indices into the input cloud of the points Y this superquadric explains.
        alpha: the paper's goodness, mean distance from Y to an even sampling S of the surface, m.
        beta: the paper's coverage, fraction of S within ``coverage_distance_m`` of Y.
        seed: index of the seed: 0..K-1 the K-means parts, K the whole cloud.
        sigma_m: fitted noise std, metres.
        cost: final negative log-likelihood per voxel centroid, nats.
    """

    superquadric: Superquadric
    inliers: NDArray[np.int64]
    alpha: float
    beta: float
    seed: int
    sigma_m: float
    cost: float


# ----------------------------------------------------------------------------- input checks
def _validate(points: ArrayLike) -> Array:
    """The cloud as (N, 3) float64, or a ValueError naming what is wrong with it."""
    cloud = as_points(points)
    n = cloud.shape[0]
    if n == 0:
        raise ValueError("the point cloud is empty; a superquadric fit needs points")
    finite = np.isfinite(cloud).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise ValueError(
            f"the point cloud has {bad.size} row(s) with NaN or inf (first at index {bad[0]}); "
            "drop them first, e.g. points[np.isfinite(points).all(axis=1)]"
        )
    if n < N_PARAMS:
        raise ValueError(
            f"the point cloud has {n} points, fewer than the {N_PARAMS} parameters of a "
            "superquadric"
        )
    spread = np.sqrt(np.maximum(np.linalg.eigvalsh(np.cov(cloud, rowvar=False)), 0.0))
    if spread[2] == 0.0:
        raise ValueError("all points of the cloud are identical; a superquadric needs a spread")
    if spread[1] <= 1e-6 * spread[2]:
        raise ValueError(
            "the points of the cloud are collinear; a superquadric needs a spread in at least "
            "two directions"
        )
    return cloud


def _downsample(cloud: Array, cfg: RecoveryConfig) -> Downsampled:
    down = downsample_to_budget(cloud, cfg.voxel_size_m, cfg.max_fit_points)
    if len(down.points) < N_PARAMS:
        raise ValueError(
            f"voxel downsampling at {down.voxel_m:.4g} m leaves {len(down.points)} points, fewer "
            f"than the {N_PARAMS} parameters of a superquadric; the cloud spans only "
            f"{np.ptp(cloud, axis=0).max():.4g} m: use a smaller voxel_size_m"
        )
    return down


# ----------------------------------------------------------------------------- fitting pieces
@dataclass(frozen=True)
class _Problem:
    """What every fit on one downsampled cloud shares."""

    points: Array
    weights: Array
    volume_m3: float
    scale_max_m: float


def _problem(down: Downsampled, cfg: RecoveryConfig) -> _Problem:
    extent = np.ptp(down.points, axis=0)
    volume = float(np.prod(extent + 2.0 * cfg.workspace_margin_m))
    return _Problem(down.points, down.counts, volume, float(np.linalg.norm(extent)))


def _fit(
    problem: _Problem,
    init: SQState,
    part: Array,
    outlier_weight: float,
    max_switches: int,
    cfg: RecoveryConfig,
) -> EMSResult:
    """EMS from ``init``; the starting noise level is the rms distance of ``part`` to ``init``."""
    r, _ = radial_residual(part, init)
    sigma2 = float(np.mean(r * r)) / 3.0
    model = MixtureModel(outlier_weight, problem.volume_m3)
    return ems_fit(
        problem.points,
        problem.weights,
        init,
        model,
        sigma2,
        problem.scale_max_m,
        max_switches,
        cfg,
    )


def _clipped(state: SQState, problem: _Problem, cfg: RecoveryConfig) -> SQState:
    return SQState(
        float(np.clip(state.eps1, cfg.eps_min, cfg.eps_max)),
        float(np.clip(state.eps2, cfg.eps_min, cfg.eps_max)),
        np.clip(state.scale, cfg.scale_min_m, max(problem.scale_max_m, cfg.scale_min_m)),
        state.rotation,
        state.translation,
    )


# ----------------------------------------------------------------------------- public API
def fit_superquadric(
    points: ArrayLike,
    init: Superquadric | None = None,
    config: RecoveryConfig | None = None,
) -> FitResult:
    """Fit one superquadric to a whole cloud by EMS (outlier weight ``config.outlier_weight``).

    Args:
        points: (N, 3) cloud, metres, world frame.
        init: starting superquadric; default: the ellipsoid with half the cloud's inertia.
        config: recovery settings; default :class:`RecoveryConfig` (same as ``configs/planner.yaml``).

    Raises:
        ValueError: an empty cloud, NaN/inf rows, fewer points than parameters, identical or
            collinear points; the message names the problem.
    """
    cfg = config or RecoveryConfig()
    cloud = _validate(points)
    down = _downsample(cloud, cfg)
    problem = _problem(down, cfg)
    if init is None:
        state = inertia_ellipsoid(down.points, cfg.scale_min_m, problem.scale_max_m)
    else:
        state = _clipped(SQState.from_superquadric(init), problem, cfg)
    res = _fit(problem, state, down.points, cfg.outlier_weight, cfg.max_switches, cfg)
    return FitResult(
        superquadric=res.state.to_superquadric(),
        inlier_probability=res.posterior[down.inverse],
        sigma_m=res.sigma_m,
        cost=res.cost,
        iterations=res.iterations,
        switches=res.switches,
    )


def part_count(cloud: Array, cfg: RecoveryConfig) -> int:
    """K for a cloud: the paper's rule on the number of ``k_count_voxel_m`` voxels it occupies.

    The paper counts the raw fused cloud of two Azure Kinects, whose pixels cover about 2 mm of
    surface at the table's distance. Counting occupied voxels of that size asks how many points
    the paper's sensors would have returned, whatever the density of our cloud; K is capped at
    ``max_parts``.
    """
    return min(paper_k(count_voxels(cloud, cfg.k_count_voxel_m)), cfg.max_parts)


def recover_hidden_superquadrics(
    points: ArrayLike,
    config: RecoveryConfig | None = None,
    seed: int | None = None,
) -> list[HiddenSuperquadric]:
    """The paper's stage one: K + 1 hidden superquadrics of a cloud.

    K-means (seeded with ``seed``) splits the downsampled cloud into K parts (:func:`part_count`).
    Each part, and the whole cloud as seed K, starts an ellipsoid with half its inertia, and EMS
    with the high outlier weight ``hidden_outlier_weight`` lets it grow into a local part. The
    inliers Y of a result are the input points whose voxel posterior exceeds
    ``inlier_threshold``; alpha and beta are computed on Y. A fit that ends with fewer than
    ``N_PARAMS`` inliers describes no part of the cloud and is left out, so at most K + 1 results
    come back, in seed order.

    Args:
        points: (N, 3) cloud, metres.
        config: recovery settings; default :class:`RecoveryConfig`.
        seed: K-means seed; ``None`` means 0, so that the planner is deterministic by default.

    Raises:
        ValueError: as :func:`fit_superquadric`.
    """
    cfg = config or RecoveryConfig()
    cloud = _validate(points)
    down = _downsample(cloud, cfg)
    problem = _problem(down, cfg)
    k = part_count(cloud, cfg)
    labels = kmeans_labels(down.points, k, 0 if seed is None else seed, cfg.kmeans_n_init)
    parts = [down.points[labels == i] for i in range(int(labels.max()) + 1)]
    parts.append(down.points)
    results = []
    for index, part in enumerate(parts):
        init = inertia_ellipsoid(part, cfg.scale_min_m, problem.scale_max_m)
        res = _fit(problem, init, part, cfg.hidden_outlier_weight, cfg.hidden_max_switches, cfg)
        inliers = np.flatnonzero(res.posterior[down.inverse] > cfg.inlier_threshold)
        if inliers.size < N_PARAMS:
            continue
        sq = res.state.to_superquadric()
        alpha, beta = alpha_beta(cloud[inliers], sq, cfg.surface_spacing_m, cfg.coverage_distance_m)
        results.append(HiddenSuperquadric(sq, inliers, alpha, beta, index, res.sigma_m, res.cost))
    return results
