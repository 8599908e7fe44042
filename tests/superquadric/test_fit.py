"""The paper's fit measures alpha and beta (hsqbench.superquadric.fit)."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.superquadric.fit import alpha_beta, coverage_beta, point_to_surface_alpha
from tests.superquadric.examples import make


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
