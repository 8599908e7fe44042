"""Rule 6's obstacles: shrunk hidden superquadrics, carved by what the cameras saw through."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.hidden_bodies import (
    body_obstacles,
    seen_free,
    shrunk_surface_samples,
)
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import Box, union_cloud, visible_mask

TABLE = np.array([0.0, 0.0, 1.0, 0.0])
CONFIG = GraspConfig()
#: A camera on the box's +x side, 40 cm away and 30 cm up.
CAMERA = np.array([[0.4, 0.0, 0.34]])


def box_seen_from(camera: np.ndarray, seed: int = 0):
    box = Box((0.03, 0.025, 0.04), center=np.array([0.0, 0.0, 0.04]))
    rng = np.random.default_rng(seed)
    cloud = union_cloud((box,), 0.002, rng)
    points = cloud.points[visible_mask(cloud.points, cloud.normals, camera[0])]
    return box, points + rng.normal(scale=0.001, size=points.shape)


def test_shrunk_samples_lie_a_margin_inside_and_thin_fits_give_none() -> None:
    sq = Superquadric(0.3, 0.8, [0.03, 0.02, 0.05], translation=[0.1, 0.0, 0.05])
    samples = shrunk_surface_samples([sq, sq], CONFIG)
    assert len(samples) > 100
    assert np.all(sq.inside_outside(samples) < 1.0)
    # Every semi-axis 3 mm shorter: no sample reaches within 2.5 mm of the true surface.
    assert np.all(sq.radial_distance(samples) > 0.8 * CONFIG.body_margin_m)
    # No gap a finger could pass: every point of the shrunk surface has a sample within 5 mm.
    m = CONFIG.body_margin_m
    shrunk = Superquadric(0.3, 0.8, [0.03 - m, 0.02 - m, 0.05 - m], translation=[0.1, 0.0, 0.05])
    dense, _ = shrunk.sample_surface(0.001)
    gap, _ = cKDTree(samples).query(dense)
    assert gap.max() <= CONFIG.body_spacing_m
    # A copy of a fit adds no samples (one per 5 mm voxel).
    assert len(samples) == len(shrunk_surface_samples([sq], CONFIG))
    wall = Superquadric(0.1, 0.1, [0.03, 0.004, 0.05])
    assert len(shrunk_surface_samples([wall], CONFIG)) == 0


def test_samples_in_front_of_what_a_camera_measured_are_free() -> None:
    box, points = box_seen_from(CAMERA)
    half = np.array(box.half_extents)
    probes = np.array(
        [
            [half[0] + 0.02, 0.0, 0.04],  # 2 cm in front of the seen +x face
            [half[0] - 0.01, 0.0, 0.04],  # 1 cm behind it, inside the box
            [-half[0] - 0.02, 0.0, 0.04],  # behind the box, in its shadow
            [0.0, 0.15, 0.03],  # beside the box: the camera saw the table there
        ]
    )
    free = seen_free(probes, points, CAMERA, CONFIG, TABLE)
    assert free.tolist() == [True, False, False, True]
    # Without the table, a ray that meets no cloud point meets nothing: free too.
    assert seen_free(probes, points, CAMERA, CONFIG).tolist() == [True, False, False, True]
    # Within the carving margin of the measured face: not free (noise, calibration).
    near = np.array([[half[0] + 0.5 * CONFIG.body_carve_margin_m, 0.0, 0.04]])
    assert not seen_free(near, points, CAMERA, CONFIG, TABLE)[0]


def test_an_overshooting_fit_keeps_only_its_hidden_part() -> None:
    box, points = box_seen_from(CAMERA)
    # A fit 4 cm too long in y (toward the seen table on both sides) and right in x.
    long = Superquadric(0.1, 0.1, [0.03, 0.065, 0.04], translation=[0.0, 0.0, 0.04])
    every = body_obstacles([long], points, CONFIG, None, TABLE)
    kept = body_obstacles([long], points, CONFIG, CAMERA, TABLE)
    assert 0 < len(kept) < len(every)
    inside = box.contains(every, tol=0.0)
    assert np.count_nonzero(box.contains(kept, tol=0.0)) == np.count_nonzero(inside)
    # What goes is outside the box, where the camera saw the table.
    assert not np.any(box.contains(every[~np.isin(every, kept).all(axis=1)], tol=0.0))
    # Nothing below the table.
    low = Superquadric(0.1, 0.1, [0.03, 0.025, 0.06], translation=[0.0, 0.0, 0.02])
    assert np.all(body_obstacles([low], points, CONFIG, None, TABLE)[:, 2] > 0.0)
