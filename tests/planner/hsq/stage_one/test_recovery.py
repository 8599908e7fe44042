"""Stage one: whole-object fits and hidden superquadrics, accuracy on known shapes, bad input.

Accuracy is measured on surfaces, not parameters (a superquadric with permuted axes can describe
the same surface): see tests/shapes.py for the two distances.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.hsq.config import RecoveryConfig, load_planner_config
from hsqbench.planner.hsq.stage_one.recovery import (
    FitResult,
    HiddenRecovery,
    HiddenSuperquadric,
    fit_superquadric,
    recover_hidden_superquadrics,
    surface_spacing,
)
from hsqbench.superquadric.fit import alpha_beta, point_to_surface_alpha
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import (
    add_noise_and_outliers,
    cylinder_with_box_on_top,
    l_of_two_boxes,
    mug_with_handle,
    random_rotation,
    random_superquadric,
    superquadric_cloud,
    surface_distance,
    union_cloud,
    view_surface_distance,
)


def _distance_to_surface(points: np.ndarray, sq: Superquadric) -> np.ndarray:
    """Euclidean distance (m) of each point to a 1 mm sampling of the surface."""
    return cKDTree(sq.sample_surface(0.001)[0]).query(points)[0]


FULL_MAX_M = 0.002
FULL_SHARE = 0.95
ONE_SIDED_MAX_M = 0.004
ONE_SIDED_SHARE = 0.90
PART_MAX_M = 0.003


# ----------------------------------------------------------------------------- single fits
def _single_fit_distances(n: int, one_sided: bool, first_seed: int) -> np.ndarray:
    out = []
    for seed in range(first_seed, first_seed + n):
        rng = np.random.default_rng(seed)
        sq = random_superquadric(rng)
        cloud = superquadric_cloud(sq, rng, one_sided=one_sided)
        fitted = fit_superquadric(cloud.points).superquadric
        if one_sided:
            out.append(view_surface_distance(sq, fitted, cloud.camera))
        else:
            out.append(surface_distance(sq, fitted))
    return np.array(out)


def test_single_fits_full_views() -> None:
    """20 random superquadrics, 1 mm noise, 20 % outliers: >= 95 % within 2 mm."""
    d = _single_fit_distances(20, one_sided=False, first_seed=0)
    assert np.mean(d < FULL_MAX_M) >= FULL_SHARE, np.round(d * 1000, 2)


def test_single_fits_one_sided_views() -> None:
    """20 one-sided views (one camera), same noise and outliers: >= 90 % within 4 mm."""
    d = _single_fit_distances(20, one_sided=True, first_seed=0)
    assert np.mean(d < ONE_SIDED_MAX_M) >= ONE_SIDED_SHARE, np.round(d * 1000, 2)


@pytest.mark.slow
def test_single_fits_full_views_100() -> None:
    d = _single_fit_distances(100, one_sided=False, first_seed=100)
    assert np.mean(d < FULL_MAX_M) >= FULL_SHARE, np.round(d * 1000, 2)


@pytest.mark.slow
def test_single_fits_one_sided_views_100() -> None:
    d = _single_fit_distances(100, one_sided=True, first_seed=100)
    assert np.mean(d < ONE_SIDED_MAX_M) >= ONE_SIDED_SHARE, np.round(d * 1000, 2)


def test_fit_result_maps_posterior_to_input_points() -> None:
    rng = np.random.default_rng(3)
    sq = Superquadric(0.5, 1.0, [0.04, 0.03, 0.05], random_rotation(rng), [0.1, 0.0, 0.2])
    surface, _ = sq.sample_surface(0.002)
    cloud, outlier = add_noise_and_outliers(surface, 0.001, 0.2, rng)
    res = fit_superquadric(cloud)
    assert isinstance(res, FitResult)
    assert res.inlier_probability.shape == (len(cloud),)
    far = outlier & (_distance_to_surface(cloud, sq) > 0.01)
    assert np.mean(res.inlier_probability[~outlier] > 0.5) > 0.95
    assert np.mean(res.inlier_probability[far] < 0.5) > 0.95
    assert 0.0002 < res.sigma_m < 0.002
    assert np.isfinite(res.cost) and res.iterations > 0


def test_fit_from_given_init_uses_it() -> None:
    """A given init is the only start: from the truth, the fit stays on it."""
    rng = np.random.default_rng(4)
    sq = random_superquadric(rng)
    cloud = superquadric_cloud(sq, rng)
    res = fit_superquadric(cloud.points, init=sq)
    assert surface_distance(sq, res.superquadric) < FULL_MAX_M
    assert res.iterations < 3 * RecoveryConfig().em_max_iterations


# ----------------------------------------------------------------------------- hidden parts
UNIONS = (l_of_two_boxes, cylinder_with_box_on_top, mug_with_handle)


def _union_part_errors(make, seed: int) -> tuple[list[float], list[HiddenSuperquadric], np.ndarray]:
    """Best mean distance (m) from each part's points to any hidden superquadric."""
    rng = np.random.default_rng(seed)
    parts = make(random_rotation(rng), rng.uniform(-0.1, 0.1, 3))
    pc = union_cloud(parts, 0.001, rng)
    cloud = pc.points + rng.normal(scale=0.001, size=pc.points.shape)
    hidden = recover_hidden_superquadrics(cloud, seed=0)
    errors = [
        min(point_to_surface_alpha(cloud[pc.labels == i], h.superquadric, 0.0015) for h in hidden)
        for i in range(len(parts))
    ]
    return errors, hidden, cloud


@pytest.mark.parametrize("make", UNIONS, ids=lambda f: f.__name__)
def test_hidden_superquadrics_find_every_part(make) -> None:
    errors, hidden, cloud = _union_part_errors(make, seed=0)
    assert max(errors) < PART_MAX_M, np.round(np.array(errors) * 1000, 2)
    for h in hidden:
        assert isinstance(h, HiddenSuperquadric)
        assert h.inliers.dtype.kind == "i" and h.inliers.min() >= 0
        assert h.inliers.max() < len(cloud) and np.unique(h.inliers).size == h.inliers.size
        cfg = RecoveryConfig()
        y = voxel_downsample(cloud, cfg.k_count_voxel_m)
        y_points = y.points[np.unique(y.inverse[h.inliers])]
        alpha, beta = alpha_beta(
            y_points, h.superquadric, surface_spacing(h.superquadric, cfg), cfg.coverage_distance_m
        )
        assert (h.alpha, h.beta) == (alpha, beta) and 0.0 < h.beta <= 1.0
        assert h.sigma_m > 0.0 and np.isfinite(h.cost)


@pytest.mark.slow
@pytest.mark.parametrize("make", UNIONS, ids=lambda f: f.__name__)
def test_hidden_superquadrics_find_every_part_12_poses(make) -> None:
    worst = [max(_union_part_errors(make, seed)[0]) for seed in range(1, 13)]
    assert max(worst) < PART_MAX_M, np.round(np.array(worst) * 1000, 2)


def test_hidden_inliers_are_the_points_near_the_surface() -> None:
    """Y maps back to the caller's array: near-surface points are in, far outliers out."""
    rng = np.random.default_rng(5)
    box = Superquadric(0.1, 0.1, [0.03, 0.02, 0.04], random_rotation(rng), [0.0, 0.1, 0.3])
    surface, _ = box.sample_surface(0.002)
    cloud, outlier = add_noise_and_outliers(surface, 0.001, 0.1, rng)
    hidden = recover_hidden_superquadrics(cloud, seed=1)
    best = min(hidden, key=lambda h: h.alpha + (1.0 - h.beta))
    assert surface_distance(box, best.superquadric) < FULL_MAX_M
    member = np.zeros(len(cloud), dtype=bool)
    member[best.inliers] = True
    far = outlier & (_distance_to_surface(cloud, box) > 0.01)
    assert member[~outlier].mean() > 0.95
    assert not member[far].any()


def test_same_seed_same_result() -> None:
    rng = np.random.default_rng(6)
    pc = union_cloud(mug_with_handle(random_rotation(rng)), 0.002, rng)
    cloud = pc.points + rng.normal(scale=0.001, size=pc.points.shape)
    a = recover_hidden_superquadrics(cloud, seed=3)
    b = recover_hidden_superquadrics(cloud.copy(), seed=3)
    assert len(a) == len(b) > 1
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.superquadric.to_vector(), y.superquadric.to_vector())
        np.testing.assert_array_equal(x.inliers, y.inliers)
        assert (x.alpha, x.beta, x.seed) == (y.alpha, y.beta, y.seed)


def _same_results(a: list[HiddenSuperquadric], b: list[HiddenSuperquadric]) -> None:
    assert len(a) == len(b)
    for x, y in zip(a, b, strict=True):
        np.testing.assert_array_equal(x.superquadric.to_vector(), y.superquadric.to_vector())
        np.testing.assert_array_equal(x.inliers, y.inliers)
        assert (x.alpha, x.beta, x.seed, x.cost) == (y.alpha, y.beta, y.seed, y.cost)


def test_draws_of_one_recovery_do_not_leak_into_each_other() -> None:
    """The planner's redraws share seed 0's fit; each draw is still that of a fresh cloud."""
    rng = np.random.default_rng(6)
    pc = union_cloud(mug_with_handle(random_rotation(rng)), 0.002, rng)
    cloud = pc.points + rng.normal(scale=0.001, size=pc.points.shape)
    shared = HiddenRecovery(cloud)
    first, other, again = shared.draw(3), shared.draw(4), shared.draw(3)
    _same_results(first, again)
    _same_results(other, HiddenRecovery(cloud).draw(4))
    assert first[0].seed == other[0].seed == 0 and len(first) > 1


def test_no_two_results_are_duplicates() -> None:
    """Seeds that turn into copies of an earlier result are dropped."""
    rng = np.random.default_rng(9)
    pc = union_cloud(cylinder_with_box_on_top(random_rotation(rng)), 0.0015, rng)
    cloud = pc.points + rng.normal(scale=0.001, size=pc.points.shape)
    cfg = RecoveryConfig()
    hidden = recover_hidden_superquadrics(cloud, cfg)
    assert [h.seed for h in hidden] == sorted(h.seed for h in hidden) and hidden[0].seed == 0
    for i, x in enumerate(hidden):
        for y in hidden[i + 1 :]:
            inter = np.intersect1d(x.inliers, y.inliers).size
            union = np.union1d(x.inliers, y.inliers).size
            assert inter < cfg.duplicate_iou * union
    everything = recover_hidden_superquadrics(cloud, RecoveryConfig(duplicate_iou=1.0))
    assert len(everything) > len(hidden)


def test_surface_sampling_of_large_fits_is_capped() -> None:
    """Object-sized fits get the configured spacing; a whole-scene fit a coarser one whose S
    holds at most ``max_surface_samples`` samples."""
    cfg = RecoveryConfig()
    box = Superquadric(0.1, 0.1, [0.08, 0.1, 0.03])  # about the YCB cracker box
    assert surface_spacing(box, cfg) == cfg.surface_spacing_m
    scene = Superquadric(0.5, 0.5, [0.25, 0.2, 0.06])
    spacing = surface_spacing(scene, cfg)
    assert spacing > cfg.surface_spacing_m
    samples, _ = scene.sample_surface(spacing)
    assert len(samples) <= cfg.max_surface_samples
    fine, _ = scene.sample_surface(cfg.surface_spacing_m)
    assert len(fine) > 3 * cfg.max_surface_samples


# ----------------------------------------------------------------------------- bad input
BAD_CLOUDS = {
    "empty": (np.zeros((0, 3)), "empty"),
    "too_few": (np.random.default_rng(0).normal(size=(10, 3)), "fewer than the 11"),
    "nan_row": (np.vstack([np.random.default_rng(0).normal(size=(50, 3)), [np.nan, 0, 0]]), "NaN"),
    "inf_row": (np.vstack([np.random.default_rng(0).normal(size=(50, 3)), [0, np.inf, 0]]), "inf"),
    "identical": (np.ones((100, 3)), "identical"),
    "collinear": (np.outer(np.linspace(0, 0.1, 100), [1.0, 2.0, 3.0]), "collinear"),
    "wrong_shape": (np.zeros((100, 2)), "shape"),
    "too_small_for_voxel": (
        np.random.default_rng(0).uniform(0.0, 0.001, size=(100, 3)),
        "voxel_size_m",
    ),
}


@pytest.mark.parametrize("name", sorted(BAD_CLOUDS))
@pytest.mark.parametrize("func", [fit_superquadric, recover_hidden_superquadrics])
def test_bad_clouds_get_a_clear_error(name: str, func) -> None:
    cloud, needle = BAD_CLOUDS[name]
    with pytest.raises(ValueError, match=needle):
        func(cloud)


def test_flat_cloud_gives_a_finite_thin_superquadric() -> None:
    """One face of a box (a planar cloud, as a camera facing it sees): no NaN, a flat fit."""
    rng = np.random.default_rng(7)
    pts = np.column_stack([rng.uniform(-0.04, 0.04, (3000, 2)), np.zeros(3000)])
    pts += rng.normal(scale=0.0005, size=pts.shape)
    res = fit_superquadric(pts)
    assert np.all(np.isfinite(res.superquadric.to_vector()))
    assert np.mean(_distance_to_surface(pts, res.superquadric) < 0.002) > 0.95
    hidden = recover_hidden_superquadrics(pts)
    assert hidden and all(np.all(np.isfinite(h.superquadric.to_vector())) for h in hidden)


def test_half_million_points_are_downsampled() -> None:
    rng = np.random.default_rng(8)
    sq = Superquadric(0.3, 0.8, [0.05, 0.04, 0.07], random_rotation(rng), [0.0, 0.0, 0.1])
    surface, _ = sq.sample_surface(0.002)
    cloud = surface[rng.integers(len(surface), size=500_000)]
    cloud += rng.normal(scale=0.001, size=cloud.shape)
    res = fit_superquadric(cloud)
    assert res.inlier_probability.shape == (500_000,)
    assert surface_distance(sq, res.superquadric) < FULL_MAX_M
    hidden = recover_hidden_superquadrics(cloud)
    assert min(surface_distance(sq, h.superquadric) for h in hidden) < FULL_MAX_M
    assert all(h.inliers.max() < 500_000 for h in hidden)


# ----------------------------------------------------------------------------- config
def test_yaml_defaults_match_the_dataclass() -> None:
    assert load_planner_config().recovery == RecoveryConfig()


@pytest.mark.parametrize(
    ("field", "value"),
    [("outlier_weight", 1.0), ("voxel_size_m", 0.0), ("eps_min", 2.5), ("start_eps", ())],
)
def test_bad_config_values_are_rejected(field: str, value) -> None:
    with pytest.raises(ValueError, match=field.split("_")[0]):
        RecoveryConfig(**{field: value})
