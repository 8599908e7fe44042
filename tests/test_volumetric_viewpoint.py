"""Depth re-projected into a virtual camera (:mod:`hsqbench.planner.learned.viewpoint`), numpy
only: exact depth of a box seen from one camera, seen again from another, against that
camera's own exact image."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.learned import viewpoint
from hsqbench.planner.learned.frames import look_at_frame
from tests.volumetric_scene import TARGET, intrinsics, render

BOX = (np.array([0.46, -0.025, 0.0]), np.array([0.54, 0.025, 0.08]))


def test_a_nearer_camera_measures_what_it_would_have_seen():
    source = render(np.array([0.62, -0.78, 0.55]), [BOX])
    near = np.array([0.5, -0.52, 0.3])  # 0.6 m from the target, 60 deg from vertical
    K = intrinsics(320, 288)
    truth = render(near, [BOX], K=K)
    T = look_at_frame(near, TARGET, np.array([0.0, 0.0, 1.0]))
    got = viewpoint.reproject(source, T, K, (320, 288), splat_px=1)
    assert np.allclose(got.T_world_camera, truth.T_world_camera)
    # The pixels whose true surface lies in a 0.3 m square around the target (a cube's worth).
    v, u = np.mgrid[:288, :320]
    rays = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones(u.shape)], -1)
    world = (rays * truth.depth_m[..., None]) @ T[:3, :3].T + T[:3, 3]
    cube = np.all(np.abs(world[..., :2] - TARGET[:2]) < 0.15, axis=-1) & (truth.depth_m > 0)
    # No hole where the source saw: the 3 x 3 splat covers the finer virtual pixels.
    assert np.mean(got.depth_m[cube] > 0) > 0.98
    # The same surface: the nearest of a splat's flat patches wins (a few mm nearer on the
    # slanted table), well under the 7.5 mm voxel.
    both = cube & (got.depth_m > 0)
    err = np.abs(got.depth_m[both] - truth.depth_m[both])
    assert np.median(err) < 0.004 and np.percentile(err, 99) < 0.01


def test_the_training_camera_sits_where_vgn_puts_it():
    target = np.array([0.15, 0.15, 0.1])
    T = viewpoint.camera_on_sphere(target, 0.6, 60.0, -90.0)
    eye = T[:3, 3]
    assert eye == pytest.approx([0.15, 0.15 - 0.6 * np.sin(np.pi / 3), 0.1 + 0.3])
    assert T[:3, 2] == pytest.approx((target - eye) / 0.6)  # looking at the target
    assert T[2, 0] == pytest.approx(0.0)  # no roll: image x stays horizontal
