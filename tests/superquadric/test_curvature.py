"""Analytic Gaussian curvature (hsqbench.superquadric.curvature)."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.superquadric.curvature import CURVATURE_AXIS_OFFSET, gaussian_curvature_local
from hsqbench.superquadric.geometry import Superquadric
from hsqbench.superquadric.primitives import EPS_MAX, EPS_MIN
from tests.superquadric.examples import random_pose


def test_curvature_of_sphere() -> None:
    radius = 0.035
    sq = Superquadric(1.0, 1.0, (radius,) * 3, *random_pose(np.random.default_rng(9)))
    points, _ = sq.sample_surface(0.003)
    # axis endpoints are included: the offset from the axis planes does not bias a smooth surface
    points = np.vstack([points, sq.to_world(np.diag(sq.scale)), sq.to_world(-np.diag(sq.scale))])
    np.testing.assert_allclose(sq.gaussian_curvature(points), 1.0 / radius**2, rtol=1e-9)
    # points off the surface are projected radially first
    off = sq.translation + 2.0 * (points - sq.translation)
    np.testing.assert_allclose(sq.gaussian_curvature(off), 1.0 / radius**2, rtol=1e-9)


def test_curvature_of_ellipsoid_matches_closed_form() -> None:
    a, b, c = 0.015, 0.05, 0.03
    sq = Superquadric(1.0, 1.0, (a, b, c), *random_pose(np.random.default_rng(10)))
    points, _ = sq.sample_surface(0.003)
    local = sq.to_local(points)
    expected = 1.0 / ((a * b * c) ** 2 * np.sum(local**2 / np.array([a, b, c]) ** 4, axis=1) ** 2)
    k = sq.gaussian_curvature(points)
    assert np.all(k > 0.0)
    np.testing.assert_allclose(k, expected, rtol=1e-6)


def _fd_curvature(sq: Superquadric, local: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """K = g^T adj(H) g / |g|^4 of rho = sqrt(G) by central differences (reference)."""

    def rho(x: np.ndarray) -> np.ndarray:
        return np.sqrt(sq.inside_outside_pow(x, local=True))

    e = np.eye(3) * h
    g = np.stack([(rho(local + e[i]) - rho(local - e[i])) / (2 * h) for i in range(3)], axis=1)
    hess = np.empty((local.shape[0], 3, 3))
    for i in range(3):
        for j in range(3):
            hess[:, i, j] = (
                rho(local + e[i] + e[j])
                - rho(local + e[i] - e[j])
                - rho(local - e[i] + e[j])
                + rho(local - e[i] - e[j])
            ) / (4 * h * h)
    adj = np.stack(
        [
            np.cross(hess[:, 1], hess[:, 2]),
            np.cross(hess[:, 2], hess[:, 0]),
            np.cross(hess[:, 0], hess[:, 1]),
        ],
        axis=2,
    )
    return np.einsum("ni,nij,nj->n", g, adj, g) / np.sum(g * g, axis=1) ** 2


@pytest.mark.parametrize("eps", [(0.5, 0.7), (1.5, 0.3), (0.3, 1.6), (1.2, 1.8), (0.2, 0.2)])
def test_curvature_matches_finite_differences(eps: tuple[float, float]) -> None:
    sq = Superquadric(*eps, (0.03, 0.04, 0.05))
    local, _ = sq.sample_surface(0.004)
    local = local[np.all(np.abs(local) > 0.003, axis=1)]  # away from the non-smooth axis planes
    local = local[np.random.default_rng(11).choice(local.shape[0], 40, replace=False)]
    k = sq.gaussian_curvature(local)
    np.testing.assert_allclose(k, _fd_curvature(sq, local), rtol=1e-4, atol=1e-2)


def test_curvature_zero_on_cube_faces_and_cylinder_side() -> None:
    cube = Superquadric(0.1, 0.1, (0.03, 0.04, 0.05))
    face = np.array(
        [[0.0, 0.0, 0.05], [0.01, -0.02, 0.05], [0.03, 0.01, -0.02], [-0.015, 0.04, 0.03]]
    )
    face /= np.sqrt(cube.inside_outside_pow(face))[:, None]
    # zero up to (fraction of the face)^(2/eps - 2): at least 1e6 below a 3 cm sphere's 1/R^2
    assert np.all(cube.gaussian_curvature(face) * 0.03**2 < 1e-6)
    # near the rounded edges it is large
    assert cube.gaussian_curvature([[0.03, 0.04, 0.05]])[0] > 1e4
    cylinder = Superquadric(0.1, 1.0, (0.03, 0.03, 0.05))
    angles = np.linspace(0.0, 2.0 * np.pi, 13)
    side = np.column_stack(
        [0.03 * np.cos(angles), 0.03 * np.sin(angles), np.linspace(-0.03, 0.03, 13)]
    )
    # eps1 = 0.1 is not exactly straight: up to 60 % of the height K is 1e3 times below 1/R^2
    assert np.all(cylinder.gaussian_curvature(side) * 0.03**2 < 1e-3)
    # the flat caps too; the rim is curved
    caps = cylinder.gaussian_curvature([[0.01, 0.0, 0.05], [0.0, -0.02, -0.05]])
    assert np.all(caps * 0.03**2 < 1e-3)
    assert cylinder.gaussian_curvature([[0.0, 0.03, 0.05]])[0] * 0.03**2 > 1.0


@pytest.mark.parametrize("eps1", [EPS_MIN, 0.5, 1.0, 1.5, 1.9, EPS_MAX])
@pytest.mark.parametrize("eps2", [EPS_MIN, 0.5, 1.0, 1.5, 1.9, EPS_MAX])
def test_curvature_finite_and_non_negative_on_sampled_surfaces(eps1: float, eps2: float) -> None:
    sq = Superquadric(eps1, eps2, (0.02, 0.03, 0.05), *random_pose(np.random.default_rng(12)))
    points, _ = sq.sample_surface(0.004)
    tips = sq.to_world(np.vstack([np.diag(sq.scale), -np.diag(sq.scale)]))
    k = sq.gaussian_curvature(np.vstack([points, tips]))
    assert np.all(np.isfinite(k))
    assert np.all(k >= 0.0)


def test_curvature_at_pinched_tip_is_large_but_finite() -> None:
    """eps > 1: unbounded at the axis endpoint, so the tip is evaluated at the documented offset."""
    sq = Superquadric(1.5, 1.5, (0.03, 0.03, 0.03))
    tip = sq.gaussian_curvature([[0.0, 0.0, 0.03]])[0]
    near = sq.gaussian_curvature([[0.003, 0.003, 0.03]])[0]
    offset = np.full(3, CURVATURE_AXIS_OFFSET * 0.03)
    offset[2] = 0.03
    assert np.isfinite(tip) and tip > 100 * near > 0
    assert tip == pytest.approx(sq.gaussian_curvature(offset[None])[0], rel=1e-3)


def test_curvature_rows_with_own_parameters() -> None:
    shapes = [
        Superquadric(0.3, 1.2, (0.02, 0.03, 0.04)),
        Superquadric(1.0, 1.0, (0.05, 0.05, 0.05)),
    ]
    local = np.array([[0.01, 0.01, 0.03], [0.0, 0.03, 0.04]])
    rows = gaussian_curvature_local(
        local,
        [s.eps1 for s in shapes],
        [s.eps2 for s in shapes],
        np.array([s.scale for s in shapes]),
    )
    single = [s.gaussian_curvature(p[None])[0] for s, p in zip(shapes, local, strict=True)]
    np.testing.assert_allclose(rows, single, rtol=1e-12)
    assert rows[1] == pytest.approx(1.0 / 0.05**2)
    with pytest.raises(ValueError, match="eps1, eps2"):
        gaussian_curvature_local(local, 2.5, 1.0, (0.01, 0.01, 0.01))
    with pytest.raises(ValueError, match="finite"):
        gaussian_curvature_local(local, 1.0, 1.0, (0.0, 0.01, 0.01))
