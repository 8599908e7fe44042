"""The paper's K rule, K-means parts and the half-inertia ellipsoid."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.hsq.config import RecoveryConfig
from hsqbench.planner.hsq.stage_one.recovery import part_count
from hsqbench.planner.hsq.stage_one.seeds import inertia_ellipsoid, kmeans_labels, paper_k
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import random_rotation


@pytest.mark.parametrize(
    ("count", "k"),
    [(0, 6), (7999, 6), (8000, 8), (11999, 8), (12000, 10), (20000, 14), (36000, 22)],
)
def test_paper_k(count: int, k: int) -> None:
    assert paper_k(count) == k


def test_part_count_counts_2mm_voxels_not_points() -> None:
    """The same surface sampled at 1 mm or 2 mm gives about the same K."""
    sq = Superquadric(0.3, 0.3, [0.08, 0.06, 0.1])
    fine, _ = sq.sample_surface(0.001)
    coarse, _ = sq.sample_surface(0.002)
    cfg = RecoveryConfig()
    assert len(fine) > 3 * len(coarse)
    assert abs(part_count(fine, cfg) - part_count(coarse, cfg)) <= 2


def _point_inertia(points: np.ndarray) -> np.ndarray:
    """Inertia tensor per unit mass of point masses about their centroid (m²)."""
    c = points - points.mean(axis=0)
    return np.eye(3) * np.einsum("ij,ij->", c, c) / len(c) - c.T @ c / len(c)


def test_ellipsoid_has_half_the_inertia_of_its_part() -> None:
    rng = np.random.default_rng(0)
    rot = random_rotation(rng)
    pts = (rng.normal(size=(5000, 3)) * [0.01, 0.03, 0.05]) @ rot.T + [0.1, 0.2, 0.3]
    e = inertia_ellipsoid(pts, 1e-4, 1.0)
    a, b, c = e.scale
    # Solid ellipsoid of unit mass, in its own frame: diag((b²+c²)/5, (a²+c²)/5, (a²+b²)/5).
    solid = np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) / 5.0
    np.testing.assert_allclose(
        e.rotation @ solid @ e.rotation.T, _point_inertia(pts) / 2, atol=1e-9
    )
    np.testing.assert_allclose(e.translation, pts.mean(axis=0))
    assert (e.eps1, e.eps2) == (1.0, 1.0) and np.linalg.det(e.rotation) > 0.999
    assert e.scale[2] == e.scale.max()


def test_ellipsoid_of_a_flat_or_single_point_part_is_clipped() -> None:
    flat = np.column_stack([np.random.default_rng(1).uniform(size=(100, 2)), np.zeros(100)])
    assert inertia_ellipsoid(flat, 0.002, 1.0).scale.min() == 0.002
    assert np.all(inertia_ellipsoid(flat[:1], 0.002, 1.0).scale == 0.002)


def test_kmeans_is_seeded_and_capped() -> None:
    pts = np.random.default_rng(2).normal(size=(500, 3))
    a = kmeans_labels(pts, 8, seed=4, n_init=1)
    np.testing.assert_array_equal(a, kmeans_labels(pts, 8, seed=4, n_init=1))
    assert set(a) == set(range(8))
    assert set(kmeans_labels(pts[:3], 8, seed=4, n_init=1)) <= {0, 1, 2}
