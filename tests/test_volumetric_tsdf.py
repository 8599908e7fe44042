"""The numpy TSDF of the vgn and giga planners (no torch needed): fused from exact depth images
of a box on a table, its zero crossing lies within one voxel of the true surfaces."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.learned import tsdf
from tests.volumetric_scene import CAMERAS, box_scene, render

VOXEL = 0.0075
TRUNC = 4 * VOXEL
BOX = (np.array([0.46, -0.03, 0.0]), np.array([0.54, 0.03, 0.1]))
#: A 40^3 cube around the box, the table 5 cm above its floor (the networks' grid).
ORIGIN = np.array([0.5 - 0.15, -0.15, -0.05])
SHAPE = (40, 40, 40)


def _distance_to_box_surface(points: np.ndarray) -> np.ndarray:
    lo, hi = BOX
    centre, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    q = np.abs(points - centre) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    return np.abs(outside + inside)


@pytest.fixture(scope="module")
def grid() -> tsdf.TSDFGrid:
    return tsdf.integrate(box_scene([BOX]), ORIGIN, VOXEL, SHAPE, TRUNC)


def test_zero_crossing_lies_within_a_voxel_of_the_plane_and_the_box(grid):
    surface = grid.surface_points()
    x, y, z = surface.T
    lo, hi = BOX
    # The table, away from the box (4 cm: beyond the truncation of its faces).
    gap = np.maximum(np.maximum(lo[0] - x, x - hi[0]), np.maximum(lo[1] - y, y - hi[1]))
    table = surface[gap > 0.04]
    assert len(table) > 500 and np.max(np.abs(table[:, 2])) < VOXEL
    # The box's top face, away from its edges.
    inner = (np.abs(x - 0.5) < 0.025) & (np.abs(y) < 0.015) & (z > 0.05)
    assert inner.sum() > 20 and np.max(np.abs(z[inner] - hi[2])) < VOXEL
    # The two faces the cameras look at (+y and -y), away from the edges.
    sides = (np.abs(x - 0.5) < 0.025) & (z > 0.02) & (z < 0.08) & (np.abs(y) < 0.07)
    assert sides.sum() > 30 and np.max(np.abs(np.abs(y[sides]) - hi[1])) < VOXEL
    # Everywhere else but at the box's edges, where a projective TSDF mixes two cameras' rays
    # (Open3D's integration does the same), the zero crossing is within a voxel too.
    error = np.minimum(np.abs(z), _distance_to_box_surface(surface))
    assert np.mean(error < VOXEL) > 0.95


def test_network_input_reads_out_like_open3d(grid):
    """0.5 at the surface, above it free space, below it the inside, 0 far from any surface."""
    x = grid.network_input()
    assert x.dtype == np.float32 and x.min() >= 0.0 and x.max() < 1.0
    centre_i, centre_j = 20, 20  # the column through the box's middle
    column = x[centre_i, centre_j]
    top_k = round((BOX[1][2] - ORIGIN[2]) / VOXEL - 0.5)  # last voxel centre inside
    assert column[top_k + 1] > 0.5 > column[top_k - 1] > 0.0
    assert column[-1] == 0.0  # 15 cm above the box: free space beyond the truncation
    # Far below the table (never seen, or deeper than the truncation): 0.
    assert x[2, 2, 0] == 0.0


def test_unseen_voxels_keep_no_weight_and_views_average():
    one = tsdf.integrate([render(CAMERAS[0], [BOX])], ORIGIN, VOXEL, SHAPE, TRUNC)
    both = tsdf.integrate(box_scene([BOX]), ORIGIN, VOXEL, SHAPE, TRUNC)
    assert one.weight.max() == 1.0 and both.weight.max() == 2.0
    assert np.count_nonzero(both.weight) > np.count_nonzero(one.weight)
    assert np.all(one.tsdf[one.weight == 0] == 1.0)


def test_bad_input_is_a_clear_error():
    with pytest.raises(ValueError, match="at least one depth image"):
        tsdf.integrate([], ORIGIN, VOXEL, SHAPE, TRUNC)
    with pytest.raises(ValueError, match="voxel_m > 0"):
        tsdf.integrate(box_scene([BOX]), ORIGIN, 0.0, SHAPE, TRUNC)
