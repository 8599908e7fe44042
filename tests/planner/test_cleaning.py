"""Cloud cleaning: flying pixels go, thin parts and the planner's index contract stay."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.cleaning import CleaningConfig, clean_cloud, isolated_mask
from hsqbench.planner.hsq.config import resolve_config
from hsqbench.planner.hsq.planner import plan_grasps
from tests.shapes import Box, Cylinder, union_cloud

CAMERA = np.array([0.62, 0.78, 0.55])
TABLE = (0.0, 0.0, 1.0, 0.0)
CONFIG = CleaningConfig(radius_m=0.008, min_neighbours=5)


def body_and_thin_bar(rng: np.random.Generator):
    """A 7 cm cylinder and a 6 x 6 mm bar beside it at 2 mm spacing, 1 mm noise; returns the
    points, a mask of the bar's points and the two primitives."""
    body = Cylinder(0.035, 0.05, center=np.array([0.5, 0.0, 0.05]))
    bar = Box((0.003, 0.003, 0.04), center=np.array([0.56, 0.0, 0.05]))
    cloud = union_cloud((body, bar), 0.002, rng)
    points = cloud.points + rng.normal(scale=0.001, size=cloud.points.shape)
    return points, cloud.labels == 1, (body, bar)


def flying_pixels(surface: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """Mixed pixels: on the camera ray through a surface point, at a uniform depth between that
    point and the table (z = 0) behind it, as the sensor model draws them."""
    hit = surface[rng.choice(len(surface), size=n, replace=False)]
    ray = hit - CAMERA
    to_table = -hit[:, 2] / ray[:, 2]
    return hit + rng.uniform(0.0, 1.0, size=n)[:, None] * to_table[:, None] * ray


def distance_to(parts, points: np.ndarray) -> np.ndarray:
    return np.min([part.distance(points) for part in parts], axis=0)


def test_flying_pixels_go_and_a_thin_bar_stays():
    rng = np.random.default_rng(0)
    surface, is_bar, parts = body_and_thin_bar(rng)
    flying = flying_pixels(surface, 300, rng)
    points = np.concatenate([surface, flying])
    drop = isolated_mask(points, CONFIG)
    far = distance_to(parts, flying) > 0.01
    assert far.sum() > 100
    assert np.all(drop[len(surface) :][far]), f"{np.sum(~drop[len(surface) :][far])} kept"
    assert not np.any(drop[: len(surface)][is_bar])
    assert np.mean(drop[: len(surface)]) < 0.005


def test_clean_cloud_maps_every_input_point_to_its_centroid_or_to_removed():
    rng = np.random.default_rng(1)
    surface, _, _ = body_and_thin_bar(rng)
    points = np.concatenate([surface[:100], [[1.0, 1.0, 1.0]], surface[100:]])
    cleaned = clean_cloud(points, CONFIG)
    assert cleaned.source[100] == -1 and cleaned.n_removed == 1
    kept = cleaned.source >= 0
    # Each kept point lies in the 2 mm voxel of its centroid (within the voxel's diagonal).
    gap = np.linalg.norm(points[kept] - cleaned.points[cleaned.source[kept]], axis=1)
    assert gap.max() <= np.sqrt(3) * CONFIG.voxel_m
    assert set(cleaned.source[kept]) == set(range(len(cleaned.points)))
    rows = np.array([0, 5])
    np.testing.assert_array_equal(
        cleaned.input_indices(rows), np.flatnonzero(np.isin(cleaned.source, rows))
    )


def test_a_cloud_already_at_the_voxel_density_is_left_as_given():
    grid = np.stack(np.meshgrid(*[np.arange(20) * 0.002] * 2, [0.0]), axis=-1).reshape(-1, 3)
    # Voxels are anchored at the cloud's minimum corner, the origin here: each grid point sits at
    # a voxel's centre, one per voxel but the first (its voxel also holds the origin).
    grid = np.concatenate([[[0.0, 0.0, 0.0]], grid + 0.001])
    cleaned = clean_cloud(grid, CONFIG)
    np.testing.assert_array_equal(cleaned.points, grid)
    # Two points per voxel: half merge, so the cloud is thinned.
    doubled = np.concatenate([grid, grid + 0.0002])
    assert len(clean_cloud(doubled, CONFIG).points) <= len(grid)


def test_voxel_zero_keeps_the_points_as_given():
    rng = np.random.default_rng(1)
    surface, _, _ = body_and_thin_bar(rng)
    cleaned = clean_cloud(surface, CleaningConfig(voxel_m=0.0))
    np.testing.assert_array_equal(cleaned.points, surface[cleaned.source >= 0])


def test_a_dense_cloud_is_thinned_to_the_density_and_budget():
    rng = np.random.default_rng(4)
    body = Cylinder(0.035, 0.05, center=np.array([0.5, 0.0, 0.05]))
    sparse = union_cloud((body,), 0.002, rng).points
    dense = union_cloud((body,), 0.0005, rng).points  # 16 x the points
    n_sparse = len(clean_cloud(sparse, CONFIG).points)
    n_dense = len(clean_cloud(dense, CONFIG).points)
    # 16 x the points at 2 mm spacing, 2 x at most after thinning (a surface crosses ~1.5 voxels
    # of its spacing's size per sample).
    assert len(dense) > 12 * len(sparse) and n_dense < 2 * len(sparse)
    # Noise makes the dense shell several voxels thick; the budget still bounds it.
    noisy = dense + rng.normal(scale=0.001, size=dense.shape)
    assert len(clean_cloud(noisy, CONFIG).points) > 2 * n_sparse
    capped = clean_cloud(noisy, CleaningConfig(max_points=n_sparse))
    assert 0.5 * n_sparse < len(capped.points) <= n_sparse


def test_zero_neighbours_turns_cleaning_off():
    points = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    assert not isolated_mask(points, CleaningConfig(min_neighbours=0)).any()
    assert isolated_mask(points, CONFIG).all()


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"radius_m": 0.0}, "radius_m"),
        ({"min_neighbours": -1}, "min_neighbours"),
        ({"voxel_m": -0.001}, "voxel_m"),
        ({"max_points": 0}, "max_points"),
        ({"min_merged_fraction": 1.5}, "min_merged_fraction"),
    ],
)
def test_bad_config_is_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CleaningConfig(**kwargs)


def test_planner_config_has_cleaning_section():
    assert resolve_config(None).cleaning == CONFIG


def test_plan_grasps_cleans_and_inliers_index_the_input():
    rng = np.random.default_rng(2)
    box = Box((0.025, 0.02, 0.04), center=np.array([0.5, 0.0, 0.04]))
    surface = union_cloud((box,), 0.003, rng).points
    surface = surface[surface[:, 2] > 0.005]  # the table hides the bottom
    flying = flying_pixels(surface, 200, rng)
    flying = flying[box.distance(flying) > 0.02]
    points = np.concatenate([flying[:30], surface, flying[30:]])
    result = plan_grasps(points, support_plane=TABLE, seed=0)
    assert result.n_removed >= len(flying)
    assert result.grasps, result.reason
    for hidden in result.hidden_superquadrics:
        # Indices into the caller's cloud: every inlier is a surface point, none a flying one.
        assert np.all(box.distance(points[hidden.inliers]) < 0.01)


def test_plan_grasps_on_a_cloud_of_isolated_points_says_why():
    points = np.random.default_rng(3).uniform(0.0, 1.0, size=(50, 3))
    result = plan_grasps(points, support_plane=TABLE)
    assert not result.grasps
    assert "cleaning removed all 50 points" in result.reason
