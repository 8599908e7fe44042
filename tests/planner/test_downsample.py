"""Voxel downsampling and the map back to the input points."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.downsample import count_voxels, downsample_to_budget, voxel_downsample


def test_centroids_counts_and_inverse() -> None:
    pts = np.random.default_rng(0).uniform(0.0, 0.1, size=(5000, 3))
    down = voxel_downsample(pts, 0.01)
    assert down.counts.sum() == len(pts) and len(down.points) == count_voxels(pts, 0.01)
    for v in (0, len(down.points) // 2, len(down.points) - 1):
        np.testing.assert_allclose(down.points[v], pts[down.inverse == v].mean(axis=0))
    # Every point lies in the voxel of its centroid.
    cell = np.floor((pts - pts.min(axis=0)) / 0.01)
    np.testing.assert_array_equal(
        cell, np.floor((down.points[down.inverse] - pts.min(axis=0)) / 0.01)
    )


def test_budget_grows_the_voxel() -> None:
    pts = np.random.default_rng(1).normal(size=(20000, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True) * 10.0  # a 10 cm sphere
    down = downsample_to_budget(pts, 0.002, 1000)
    assert len(down.points) <= 1000 and down.voxel_m > 0.002
    assert len(downsample_to_budget(pts, 0.02, 1000).points) == count_voxels(pts, 0.02)


def test_huge_extent_uses_the_exact_path() -> None:
    """A grid too large for one int64 key per voxel still downsamples correctly."""
    pts = np.array([[0.0, 0.0, 0.0], [1e6, 1e6, 1e6], [1e-4, 0.0, 0.0]])
    down = voxel_downsample(pts, 0.001)
    assert len(down.points) == 2 and down.inverse[0] == down.inverse[2]


def test_bad_voxel_size() -> None:
    with pytest.raises(ValueError, match="voxel"):
        voxel_downsample(np.zeros((3, 3)), 0.0)


def test_an_empty_cloud_downsamples_to_an_empty_cloud() -> None:
    # a privileged planner plans with whatever was perceived, which may be nothing
    down = voxel_downsample(np.zeros((0, 3)), 0.01)
    assert down.points.shape == (0, 3) and len(down.counts) == 0 and len(down.inverse) == 0
    assert count_voxels(np.zeros((0, 3)), 0.01) == 0
