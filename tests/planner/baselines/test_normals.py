"""PCA normals, their outward orientation, and the antipodal sampler's ray casting."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.baselines.antipodal import (
    cast_rays,
    closing_lines,
    pair_dots,
    sample_antipodal_pairs,
)
from hsqbench.planner.baselines.config import AntipodalConfig
from hsqbench.planner.baselines.normals import (
    estimate_normals,
    neighbourhood_centroids,
    orient_outward,
)
from tests.shapes import Box, Cylinder, union_cloud


def test_pair_dots_is_the_matrix_product() -> None:
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(7, 3)), rng.normal(size=(5, 3))
    np.testing.assert_allclose(pair_dots(a, b), a @ b.T, atol=1e-12)


def test_normals_of_a_noisy_tilted_plane() -> None:
    rng = np.random.default_rng(1)
    normal = np.array([1.0, 2.0, 2.0]) / 3.0
    u = np.cross(normal, [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(normal, u)
    st = rng.uniform(-0.05, 0.05, size=(3000, 2))
    points = st[:, :1] * u + st[:, 1:] * v + rng.normal(scale=0.0005, size=(3000, 1)) * normal
    est = estimate_normals(points, 20)
    angle = np.degrees(np.arccos(np.clip(np.abs(est.normals @ normal), 0.0, 1.0)))
    assert np.median(angle) < 4.0 and np.quantile(angle, 0.99) < 12.0
    np.testing.assert_allclose(np.linalg.norm(est.normals, axis=1), 1.0)
    # Planar: the smallest eigenvalue is a small share of the spread.
    assert np.median(est.variation) < 0.02


def test_curved_surface_has_more_variation_than_a_plane() -> None:
    rng = np.random.default_rng(2)
    d = rng.normal(size=(3000, 3))
    ball = 0.01 * d / np.linalg.norm(d, axis=1, keepdims=True)
    plane = np.column_stack([rng.uniform(-0.02, 0.02, (3000, 2)), np.zeros(3000)])
    assert np.median(estimate_normals(ball, 30).variation) > 5 * np.median(
        estimate_normals(plane, 30).variation + 1e-6
    )


@pytest.mark.parametrize(
    "part",
    [
        Box((0.03, 0.02, 0.05), center=np.array([0.2, 0.0, 0.05])),
        Cylinder(0.03, 0.05, center=np.array([0.0, -0.1, 0.05])),
    ],
)
def test_orientation_points_out_of_convex_objects(part) -> None:
    rng = np.random.default_rng(3)
    cloud = union_cloud((part,), 0.003, rng)
    points = cloud.points + rng.normal(scale=0.001, size=cloud.points.shape)
    est = estimate_normals(points, 20)
    # Start from random signs: orientation must not depend on them.
    flipped = est.normals * rng.choice([-1.0, 1.0], size=(len(points), 1))
    oriented = orient_outward(points, flipped, 0.05, 0.01)
    agree = np.einsum("ij,ij->i", oriented, cloud.normals)
    assert np.mean(agree > 0.0) > 0.99
    np.testing.assert_array_equal(np.abs(oriented), np.abs(flipped))


def test_neighbourhood_centroid_of_a_lone_point_is_its_voxel() -> None:
    points = np.array([[0.0, 0.0, 0.0], [0.001, 0.0, 0.0], [1.0, 0.0, 0.0]])
    centres = neighbourhood_centroids(points, 0.05, 0.01)
    np.testing.assert_allclose(centres[2], points[2])
    np.testing.assert_allclose(centres[0], [0.0005, 0.0, 0.0])


def test_orientation_voxel_must_fit_the_radius() -> None:
    with pytest.raises(ValueError, match="radius / sqrt"):
        neighbourhood_centroids(np.zeros((5, 3)), 0.01, 0.01)


@pytest.mark.parametrize(("k", "n", "needle"), [(2, 100, "k >= 3"), (20, 10, "at least 20")])
def test_bad_normal_requests_are_refused(k, n, needle) -> None:
    with pytest.raises(ValueError, match=needle):
        estimate_normals(np.random.default_rng(0).normal(size=(n, 3)), k)


def two_planes(gap: float, n: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Points on z = 0 (normal -z) and z = gap (normal +z): a slab, outward normals."""
    g = np.linspace(-0.02, 0.02, n)
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    lower = np.column_stack([xy, np.zeros(len(xy))])
    upper = np.column_stack([xy, np.full(len(xy), gap)])
    normals = np.concatenate(
        [np.tile([0.0, 0.0, -1.0], (len(xy), 1)), np.tile([0, 0, 1.0], (len(xy), 1))]
    )
    return np.concatenate([lower, upper]), normals


def test_rays_hit_the_far_side_not_their_own_surface() -> None:
    points, _ = two_planes(0.03)
    origins = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.05, 0.05, 0.0]])
    directions = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 0.0, 1.0]])
    index, found = cast_rays(points, origins, directions, 0.001, 0.006)
    np.testing.assert_array_equal(found, [True, False, False])
    assert points[index[0], 2] == pytest.approx(0.03)
    assert np.hypot(*points[index[0], :2]) < 0.001


def test_first_hit_is_the_nearest_surface_along_the_ray() -> None:
    near, _ = two_planes(0.02)
    far = near + np.array([0.0, 0.0, 0.05])
    points = np.concatenate([far, near])  # the far plane first in memory
    index, found = cast_rays(
        points, np.array([[0.0, 0.0, -0.01]]), np.array([[0, 0, 1.0]]), 0.001, 0.0
    )
    assert found[0] and points[index[0], 2] == pytest.approx(0.0)


def test_slab_pairs_are_antipodal_and_their_lines_approach_from_above() -> None:
    points, normals = two_planes(0.03)
    # Tilt the slab on its side: the pairs close horizontally, along x.
    rot = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    points, normals = points @ rot.T, normals @ rot.T
    pairs = sample_antipodal_pairs(
        points, normals, AntipodalConfig(n_samples=100), np.random.default_rng(0)
    )
    assert pairs.n_samples == 100 and len(pairs) > 80
    np.testing.assert_allclose(np.linalg.norm(pairs.q - pairs.p, axis=1), 0.03, atol=0.002)
    # A hit may lie up to the ray radius off the ray: the axis tilts by at most atan(r / width).
    tilt = np.arctan(AntipodalConfig().ray_radius_m / 0.03) + 1e-9
    assert np.all(pairs.theta_p <= tilt) and np.all(pairs.theta_q <= tilt)
    lines = closing_lines(pairs, np.array([0.0, 0.0, 1.0]))
    assert np.all(np.abs(lines.directions[:, 0]) > 0.99)
    # Roll 0 approaches as nearly straight down as a line allows: -z minus its part along d.
    np.testing.assert_allclose(-lines.approach0[:, 2], np.sqrt(1 - lines.directions[:, 2] ** 2))
    np.testing.assert_allclose(lines.half_lengths, 0.015, atol=0.001)


def test_a_partner_whose_normal_opposes_the_ray_is_not_antipodal() -> None:
    # Every normal points down: rays from the lower plane (correctly outward, -z) go up and hit
    # the upper plane, whose normal faces back along the ray: outside its friction cone. Rays
    # from the upper plane go up and leave the cloud.
    points, _ = two_planes(0.03)
    down = np.tile([0.0, 0.0, -1.0], (len(points), 1))
    config = AntipodalConfig(n_samples=100)
    pairs = sample_antipodal_pairs(points, down, config, np.random.default_rng(0))
    assert 20 < pairs.n_hits < 80 and len(pairs) == 0


def test_vertical_lines_get_a_horizontal_approach() -> None:
    points, normals = two_planes(0.03)
    pairs = sample_antipodal_pairs(
        points, normals, AntipodalConfig(n_samples=20), np.random.default_rng(0)
    )
    lines = closing_lines(pairs, np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(
        np.einsum("ij,ij->i", lines.approach0, lines.directions), 0.0, atol=1e-6
    )
    np.testing.assert_allclose(np.linalg.norm(lines.approach0, axis=1), 1.0)
