"""Tests of hsqbench.superquadric: implicit function, sampling, normals, curvature, fit measures, mesh."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from hsqbench.superquadric import (
    Superquadric,
    alpha_beta,
    coverage_beta,
    point_to_surface_alpha,
)

# (eps1, eps2, scale in metres): sphere, near-cube, cylinder, octahedron, pinched, extremes.
SHAPES = {
    "sphere": (1.0, 1.0, (0.04, 0.04, 0.04)),
    "ellipsoid": (1.0, 1.0, (0.015, 0.05, 0.03)),
    "cube": (0.1, 0.1, (0.03, 0.04, 0.05)),
    "cylinder": (0.1, 1.0, (0.03, 0.03, 0.05)),
    "octahedron": (2.0, 2.0, (0.04, 0.04, 0.04)),
    "octahedron_aniso": (2.0, 2.0, (0.02, 0.04, 0.05)),
    "pinched": (1.5, 1.5, (0.04, 0.03, 0.05)),
    "star_prism": (0.2, 1.8, (0.03, 0.04, 0.05)),
    "pinched_box": (1.8, 0.2, (0.03, 0.04, 0.05)),
    "eps_min": (0.05, 0.05, (0.05, 0.03, 0.04)),
    "eps_min_max": (0.05, 2.0, (0.03, 0.03, 0.06)),
    "bipyramid": (2.0, 0.05, (0.076, 0.047, 0.06)),
}


def random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return Rotation.random(random_state=rng).as_matrix(), rng.uniform(-0.5, 0.5, 3)


def make(name: str, rng: np.random.Generator | None = None) -> Superquadric:
    e1, e2, scale = SHAPES[name]
    if rng is None:
        return Superquadric(e1, e2, scale)
    rotation, translation = random_pose(rng)
    return Superquadric(e1, e2, scale, rotation, translation)


def nn_distances(points: np.ndarray) -> np.ndarray:
    return cKDTree(points).query(points, k=2)[0][:, 1]


# ------------------------------------------------------------------------------------ sampling
@pytest.mark.parametrize("name", sorted(SHAPES))
def test_samples_lie_on_surface(name: str) -> None:
    sq = make(name, np.random.default_rng(1))
    points, _ = sq.sample_surface(0.003)
    assert points.shape[0] > 100
    np.testing.assert_allclose(sq.inside_outside(points), 1.0, rtol=1e-6)


@pytest.mark.parametrize("eps1", [0.1, 0.4, 1.0, 1.5, 2.0])
@pytest.mark.parametrize("eps2", [0.1, 0.6, 1.0, 2.0])
def test_samples_on_surface_across_exponents(eps1: float, eps2: float) -> None:
    rng = np.random.default_rng(int(100 * eps1 + 10 * eps2))
    rotation, translation = random_pose(rng)
    sq = Superquadric(eps1, eps2, rng.uniform(0.01, 0.06, 3), rotation, translation)
    points, normals = sq.sample_surface(0.004)
    np.testing.assert_allclose(sq.inside_outside(points), 1.0, rtol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(SHAPES))
@pytest.mark.parametrize("spacing", [0.002, 0.005])
def test_sampling_is_even(name: str, spacing: float) -> None:
    sq = make(name, np.random.default_rng(2))
    points, _ = sq.sample_surface(spacing)
    d = nn_distances(points)
    assert d.std() / d.mean() < 0.3
    assert 0.7 * spacing < d.mean() < 1.3 * spacing


@pytest.mark.parametrize("name", ["sphere", "cube", "cylinder", "octahedron", "pinched"])
def test_sampling_leaves_no_holes(name: str) -> None:
    """Random surface points (from a much finer sampling) are near some sample: no gaps."""
    sq = make(name)
    spacing = 0.004
    coarse, _ = sq.sample_surface(spacing)
    fine, _ = sq.sample_surface(spacing / 8)
    gap = cKDTree(coarse).query(fine)[0]
    assert gap.max() < 1.0 * spacing
    assert gap.mean() < 0.5 * spacing


def test_sampling_even_on_random_shapes() -> None:
    rng = np.random.default_rng(7)
    for _ in range(15):
        e1, e2 = rng.choice([0.05, 2.0, *rng.uniform(0.05, 2.0, 4)], size=2)
        sq = Superquadric(e1, e2, rng.uniform(0.01, 0.05, 3), *random_pose(rng))
        spacing = rng.uniform(0.003, 0.005)
        points, _ = sq.sample_surface(spacing)
        d = nn_distances(points)
        assert d.std() / d.mean() < 0.3, (e1, e2, sq.scale)
        assert 0.7 * spacing < d.mean() < 1.3 * spacing, (e1, e2, sq.scale)
        fine, _ = sq.sample_surface(spacing / 4)
        assert cKDTree(points).query(fine)[0].max() < 1.1 * spacing, (e1, e2, sq.scale)


def test_sample_count_scales_with_area() -> None:
    sq = make("sphere")
    n = sq.sample_surface(0.002)[0].shape[0]
    area = 4.0 * np.pi * 0.04**2
    # one sample per spacing^2 (square grid) up to the seams and the sphere's distortion
    assert 0.8 < n * 0.002**2 / area < 1.3


@pytest.mark.parametrize("spacing", [0.0, -0.001, np.nan, np.inf])
def test_sampling_rejects_bad_spacing(spacing: float) -> None:
    with pytest.raises(ValueError, match="spacing"):
        make("sphere").sample_surface(spacing)


def test_sampling_rejects_too_many_points() -> None:
    with pytest.raises(ValueError, match="MAX_SAMPLE_NODES"):
        make("sphere").sample_surface(1e-5)


# ------------------------------------------------------------------------------------ normals
@pytest.mark.parametrize("name", sorted(SHAPES))
def test_normals_unit_outward_and_match_finite_differences(name: str) -> None:
    rng = np.random.default_rng(3)
    sq = make(name, rng)
    points, normals = sq.sample_surface(0.004)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
    # outward: G grows along the normal (valid for pinched shapes too)
    step = 1e-6
    assert np.all(sq.inside_outside_pow(points + step * normals) > 1.0)
    assert np.all(sq.inside_outside_pow(points - step * normals) < 1.0)
    if SHAPES[name][0] <= 1.0 and SHAPES[name][1] <= 1.0:
        assert np.all(np.einsum("ij,ij->i", normals, points - sq.translation) > 0.0)
    # central differences of G; keep away from the axis planes where eps > 1 makes G non-smooth
    local = sq.to_local(points)
    smooth = np.all(np.abs(local) > 1e-3, axis=1)
    h = 1e-7
    fd = np.stack(
        [
            sq.inside_outside_pow(points[smooth] + h * e)
            - sq.inside_outside_pow(points[smooth] - h * e)
            for e in np.eye(3)
        ],
        axis=1,
    )
    fd /= np.linalg.norm(fd, axis=1, keepdims=True)
    assert smooth.sum() > 50
    np.testing.assert_allclose(np.einsum("ij,ij->i", fd, normals[smooth]), 1.0, atol=1e-5)


# ------------------------------------------------------------------------------------ alpha / beta
def test_alpha_zero_for_points_on_surface() -> None:
    sq = make("cube", np.random.default_rng(4))
    spacing = 0.002
    cloud, _ = sq.sample_surface(0.0007)
    alpha = point_to_surface_alpha(cloud, sq, spacing)
    # discretisation bias only: about 0.4 spacing on average for a square grid
    assert alpha < 0.5 * spacing
    # and the samples themselves give exactly zero
    samples, _ = sq.sample_surface(spacing)
    assert point_to_surface_alpha(samples, sq, spacing) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("name", ["sphere", "cube", "ellipsoid"])
def test_alpha_measures_normal_offset(name: str) -> None:
    sq = make(name, np.random.default_rng(5))
    cloud, normals = sq.sample_surface(0.002)
    alpha = point_to_surface_alpha(cloud + 0.003 * normals, sq, 0.001)
    assert alpha == pytest.approx(0.003, abs=0.0003)


def test_beta_full_and_half_cloud() -> None:
    sq = make("ellipsoid", np.random.default_rng(6))
    cloud, _ = sq.sample_surface(0.0015)
    spacing, d_th = 0.002, 0.002
    assert coverage_beta(cloud, sq, spacing, d_th) > 0.99
    side = (cloud - sq.translation) @ sq.rotation[:, 1] > 0.0
    half = coverage_beta(cloud[side], sq, spacing, d_th)
    assert 0.45 < half < 0.56
    alpha, beta = alpha_beta(cloud[side], sq, spacing, d_th)
    assert beta == half
    assert alpha == point_to_surface_alpha(cloud[side], sq, spacing)


def test_beta_far_cloud_is_zero() -> None:
    sq = make("sphere")
    assert coverage_beta(np.full((10, 3), 1.0), sq, 0.003, 0.005) == 0.0


@pytest.mark.parametrize("func", ["alpha", "beta", "both"])
def test_fit_measures_reject_empty_cloud(func: str) -> None:
    sq = make("sphere")
    empty = np.zeros((0, 3))
    with pytest.raises(ValueError, match="empty"):
        if func == "alpha":
            point_to_surface_alpha(empty, sq, 0.003)
        elif func == "beta":
            coverage_beta(empty, sq, 0.003, 0.005)
        else:
            alpha_beta(empty, sq, 0.003, 0.005)


def test_fit_measures_reject_bad_inputs() -> None:
    sq = make("sphere")
    with pytest.raises(ValueError, match="NaN"):
        point_to_surface_alpha(np.full((3, 3), np.nan), sq, 0.003)
    with pytest.raises(ValueError, match="d_th"):
        coverage_beta(np.zeros((3, 3)), sq, 0.003, 0.0)
    with pytest.raises(ValueError, match="shape"):
        point_to_surface_alpha(np.zeros((3, 2)), sq, 0.003)
