"""Rule 7, the release (hsqbench.planner.release): poses at which the object would rest on both
open fingers go; a part over one finger, or nothing over them, keeps the pose."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.candidates import roll_frames
from hsqbench.planner.config import GraspConfig
from hsqbench.planner.release import (
    _in_grasp_frames,
    _ray_hits_box,
    hangs_on_both_fingers,
    open_finger_boxes,
)
from tests.test_elimination import GRIPPER, one_line, patch

CONFIG = GraspConfig()


def rim(x: float, z: float = 0.05) -> np.ndarray:
    return patch((x, 0.0, z), (0, 0, 1), radius=0.006)


def hanging(cloud: np.ndarray, direction=(1.0, 0.0, 0.0)) -> np.ndarray:
    cands = one_line(0.02, direction=direction)
    return hangs_on_both_fingers(cloud, cands, np.array([0]), GRIPPER, CONFIG)[0]


def test_the_open_fingers_sit_just_outside_the_full_opening() -> None:
    boxes = open_finger_boxes(GRIPPER)
    half = GRIPPER.max_opening_m / 2
    assert boxes[0, 0, 0] == pytest.approx(half) and boxes[1, 1, 0] == pytest.approx(-half)
    assert boxes[0, 1, 0] - boxes[0, 0, 0] == pytest.approx(GRIPPER.finger_thickness_m)
    assert boxes[0, 1, 2] == pytest.approx(GRIPPER.fingertip_overhang_m)


def test_ray_box_test_finds_hits_below_and_within_reach_only() -> None:
    box = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    q = np.array([[0.5, 0.5, 3.0], [0.5, 0.5, 3.0], [1.5, 0.5, 3.0], [0.5, 0.5, -1.0]])
    down = np.array([0.0, 0.0, -1.0])
    assert _ray_hits_box(q, down, box, 5.0).tolist() == [True, True, False, False]
    assert _ray_hits_box(q[:1], down, box, 1.5).tolist() == [False]  # 2 m above: out of reach
    slanted = np.array([1.0, 0.0, -1.0]) / np.sqrt(2)
    assert _ray_hits_box(np.array([[-1.5, 0.5, 2.5]]), slanted, box, 5.0).tolist() == [True]


def test_a_rim_over_both_fingers_removes_the_rolls_that_put_the_fingers_under_it() -> None:
    hit = hanging(np.concatenate([rim(0.05), rim(-0.05)]))
    assert hit.any()
    # Roll 0 approaches along +z (one_line): the palm is below, the fingers' tips point up at
    # the rim from under it; the rolls with a horizontal approach have it over both fingers.
    rolls = np.rad2deg(np.arange(hit.size) * 2 * np.pi / hit.size)
    assert hit[np.isclose(rolls, 90.0)].all() and hit[np.isclose(rolls, 270.0)].all()


def test_nothing_or_one_side_over_the_fingers_keeps_every_roll() -> None:
    assert not hanging(rim(0.05)).any()  # one finger: the object tips off it
    assert not hanging(np.concatenate([rim(0.03), rim(-0.03)])).any()  # inside the opening
    assert not hanging(np.concatenate([rim(0.05, z=-0.06), rim(-0.05, z=-0.06)])).any()  # below
    too_high = CONFIG.release_fall_m + 0.05
    assert not hanging(np.concatenate([rim(0.05, too_high), rim(-0.05, too_high)])).any()


def test_a_stray_point_per_finger_is_not_a_rim() -> None:
    two = np.array([[0.05, 0.0, 0.05], [-0.05, 0.0, 0.05]])
    assert CONFIG.release_min_points == 2 and not hanging(two).any()
    # Two points 8 mm apart (separate 5 mm voxels) over each finger are a surface.
    assert hanging(np.vstack([two, two + np.array([0.0, 0.008, 0.0])])).any()


def test_grasp_frame_coordinates_match_the_candidates_frames() -> None:
    rng = np.random.default_rng(3)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    a0 = np.cross(d, rng.normal(size=3))
    a0 /= np.linalg.norm(a0)
    rolls = np.deg2rad(np.arange(0, 360, 10.0))
    frames = roll_frames(d[None], a0[None], rolls)[0]  # (R, 3, 3)
    e2 = np.cross(d, a0)
    basis = np.stack([d, a0, e2, np.cross(a0, d), np.cross(e2, d)])
    vec = rng.normal(size=(4, 3))
    got = _in_grasp_frames(vec @ basis.T, np.cos(rolls), np.sin(rolls))
    np.testing.assert_allclose(got, np.einsum("rji,pj->pri", frames, vec), atol=1e-12)
