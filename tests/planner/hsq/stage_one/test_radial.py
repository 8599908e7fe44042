"""Scaled radial distance and the analytic Jacobian of the radial distance."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.hsq.stage_one.radial import SQState, apply_increment, evaluate, jacobian
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import random_rotation

BOUNDS = ((0.01, 5.0), (1e-6, 10.0))


def _random_sq(rng: np.random.Generator) -> Superquadric:
    e1, e2 = rng.uniform(0.1, 2.0, size=2)
    return Superquadric(e1, e2, rng.uniform(0.01, 0.1, 3), random_rotation(rng), rng.normal(size=3))


@pytest.mark.parametrize("seed", range(6))
def test_residuals_match_the_radial_distance(seed: int) -> None:
    rng = np.random.default_rng(seed)
    sq = _random_sq(rng)
    pts = sq.translation + rng.normal(scale=0.08, size=(300, 3))
    ev = evaluate(pts.T.copy(), SQState.from_superquadric(sq))
    np.testing.assert_allclose(np.abs(ev.r), sq.radial_distance(pts), atol=1e-12)
    outside = sq.inside_outside(pts) > 1.0
    assert np.all((ev.r > 0) == outside)
    # d = r cos(theta): never longer than r, same sign.
    assert np.all(np.abs(ev.d) <= np.abs(ev.r) + 1e-15) and np.all(ev.d * ev.r >= 0.0)


def test_scaled_distance_is_the_normal_offset_on_a_flat_face() -> None:
    """Off a box face, d is the Euclidean offset even where the ray from the centre is oblique."""
    box = Superquadric(0.1, 0.1, [0.1, 0.02, 0.05])
    # Points 2 mm above the large +y face, far from its centre: rays meet the face obliquely.
    pts = np.column_stack([np.linspace(-0.07, 0.07, 15), np.full(15, 0.022), np.zeros(15)])
    ev = evaluate(pts.T.copy(), SQState.from_superquadric(box))
    np.testing.assert_allclose(ev.d, 0.002, rtol=0.02)
    assert ev.r.max() > 0.004  # the plain radial distance overstates it


@pytest.mark.parametrize("seed", range(6))
def test_jacobian_matches_finite_differences(seed: int) -> None:
    rng = np.random.default_rng(seed)
    sq = _random_sq(rng)
    state = SQState.from_superquadric(sq)
    pts = sq.translation + rng.normal(scale=0.06, size=(200, 3))
    jac = jacobian(evaluate(pts.T.copy(), state))
    h = 1e-7
    for k in range(11):
        step = np.zeros(11)
        step[k] = h
        plus = evaluate(pts.T.copy(), apply_increment(state, step, *BOUNDS)).r
        minus = evaluate(pts.T.copy(), apply_increment(state, -step, *BOUNDS)).r
        numeric = (plus - minus) / (2 * h)
        np.testing.assert_allclose(jac[k], numeric, rtol=1e-4, atol=1e-6 * np.abs(numeric).max())


def test_jacobian_on_selected_rows() -> None:
    rng = np.random.default_rng(9)
    sq = _random_sq(rng)
    pts = sq.translation + rng.normal(scale=0.05, size=(50, 3))
    ev = evaluate(pts.T.copy(), SQState.from_superquadric(sq))
    rows = np.array([3, 7, 40])
    np.testing.assert_array_equal(jacobian(ev, rows), jacobian(ev)[:, rows])


def test_centre_point_and_extreme_exponents_stay_finite() -> None:
    for eps in (0.1, 2.0):
        sq = Superquadric(eps, eps, [0.002, 0.05, 0.3])
        pts = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1e-12, 0.0], [5.0, 5.0, 5.0]])
        ev = evaluate(pts.T.copy(), SQState.from_superquadric(sq))
        assert np.all(np.isfinite(ev.d)) and np.all(np.isfinite(jacobian(ev)))


def test_increment_is_clipped_to_bounds() -> None:
    state = SQState(1.0, 1.0, np.full(3, 0.05), np.eye(3), np.zeros(3))
    out = apply_increment(
        state, np.r_[5.0, -5.0, 3.0, -9.0, 0.0, np.zeros(6)], (0.1, 2.0), (0.002, 0.2)
    )
    assert (out.eps1, out.eps2) == (2.0, 0.1)
    np.testing.assert_allclose(out.scale, [0.2, 0.002, 0.05])
