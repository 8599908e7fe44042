"""Per-row superquadric evaluation: inside-outside, contact distance and gradient."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.hsq.stage_two.shape_rows import ShapeRows
from hsqbench.superquadric.geometry import Superquadric

SQS = [
    Superquadric(1.0, 1.0, [0.03, 0.02, 0.05]),
    Superquadric(0.1, 0.1, [0.03, 0.02, 0.05]),
    Superquadric(0.3, 1.7, [0.01, 0.04, 0.02]),
]


def test_rows_match_each_superquadric() -> None:
    rng = np.random.default_rng(0)
    index = rng.integers(0, len(SQS), size=200)
    local = rng.uniform(-0.06, 0.06, size=(200, 3))
    rows = ShapeRows.of(SQS, index)
    expected = np.array(
        [
            SQS[i].inside_outside_pow(p[None], local=True)[0]
            for i, p in zip(index, local, strict=True)
        ]
    )
    np.testing.assert_allclose(rows.inside_outside_pow(local), expected, rtol=1e-12)


def test_contact_distance_on_known_shapes() -> None:
    rows = ShapeRows.of(SQS, np.array([0, 0, 1, 1]))
    origins = np.array([[0.0, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.01, 0.03], [0.0, 0.0, 0.0]])
    dirs = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    t = rows.contact_distance(origins, dirs)
    # Ellipsoid: along x from the centre, a; from y = b/2, a sqrt(1 - 1/4).
    assert t[0] == pytest.approx(0.03, rel=1e-9)
    assert t[1] == pytest.approx(0.03 * np.sqrt(0.75), rel=1e-9)
    # Near-box: flat faces.
    assert t[2] == pytest.approx(0.03, rel=1e-2)
    assert t[3] == pytest.approx(0.05, rel=1e-9)


def test_gradient_points_along_the_exact_normal() -> None:
    rng = np.random.default_rng(1)
    index = rng.integers(0, len(SQS), size=50)
    rows = ShapeRows.of(SQS, index)
    directions = rng.normal(size=(50, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    on_surface = rows.contact_distance(np.zeros((50, 3)), directions)[:, None] * directions
    grad = rows.gradient(on_surface)
    grad /= np.linalg.norm(grad, axis=1, keepdims=True)
    exact = np.array([SQS[i].normals(p[None])[0] for i, p in zip(index, on_surface, strict=True)])
    np.testing.assert_allclose(grad, exact, atol=1e-5)
