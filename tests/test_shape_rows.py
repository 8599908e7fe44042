"""Per-row superquadric evaluation: inside-outside, contact distance and Gaussian curvature."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.shape_rows import ShapeRows
from hsqbench.superquadric import Superquadric

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


def test_gaussian_curvature_of_sphere_ellipsoid_and_cylinder_side() -> None:
    sphere = Superquadric(1.0, 1.0, [0.02, 0.02, 0.02])
    ellipsoid = Superquadric(1.0, 1.0, [0.05, 0.02, 0.03])
    cylinder = Superquadric(0.1, 1.0, [0.03, 0.03, 0.05])
    rows = ShapeRows.of([sphere, ellipsoid, cylinder], np.array([0, 0, 1, 1, 2]))
    pts = np.array(
        [
            [0.02, 0.0, 0.0],
            [0.02 / np.sqrt(3)] * 3,
            [0.05, 0.0, 0.0],  # tip of the long axis: K = a^2 / (b^2 c^2)
            [0.0, 0.02, 0.0],  # tip of the middle axis: K = b^2 / (a^2 c^2)
            [0.03, 0.0, 0.0],  # cylinder side: one principal curvature is zero
        ]
    )
    k = rows.gaussian_curvature(pts)
    np.testing.assert_allclose(k[:2], 1 / 0.02**2, rtol=1e-4)
    assert k[2] == pytest.approx(0.05**2 / (0.02**2 * 0.03**2), rel=1e-4)
    assert k[3] == pytest.approx(0.02**2 / (0.05**2 * 0.03**2), rel=1e-4)
    assert abs(k[4]) < 1e-3 / 0.03**2
