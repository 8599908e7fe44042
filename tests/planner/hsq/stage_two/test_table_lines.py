"""Closing lines near the table: levelled, lifted, re-centred, or left alone."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.elimination import approach_openings, line_boxes, table_clear
from hsqbench.planner.hsq.stage_two.synthesis import synthesize
from hsqbench.planner.hsq.stage_two.table_lines import LEVELLED, PINCHED, level_table_lines
from hsqbench.superquadric.geometry import Superquadric

TABLE = np.array([0.0, 0.0, 1.0, 0.0])
GRIPPER = GripperModel()
CONFIG = GraspConfig()


def lying_bar(radius: float, height: float, tilt_deg: float = 0.0, eps2: float = 1.0):
    """A bar 20 cm long along world y, lying on the table with its axis ``height`` above it, its
    cross-section (local x, y) round (eps2 = 1) or square (eps2 -> 0.1); tilted about world y."""
    rot = Rotation.from_euler("xy", [90.0, tilt_deg], degrees=True).as_matrix()
    return Superquadric(0.1, eps2, [radius, radius, 0.1], rot, [0.5, 0.0, height])


def repaired(sq: Superquadric):
    """Candidates of ``sq`` after the repair, the repaired lines that cross the bar (not along
    its length: too wide for any gripper), and the lines' centres and directions before."""
    cands = synthesize([sq], CONFIG)
    before = cands.lines.centres.copy(), cands.lines.directions.copy()
    idx = level_table_lines(cands, [sq], TABLE, GRIPPER, CONFIG)
    across = np.abs(cands.lines.directions[idx, 1]) < 0.5
    return cands, idx[across], before


def clear_rolls(cands, lines):
    boxes = line_boxes(
        GRIPPER,
        approach_openings(cands.lines.half_lengths[lines], GRIPPER, CONFIG),
        CONFIG.approach_distance_m,
    )
    return table_clear(cands, lines, boxes, TABLE, CONFIG.table_clearance_m)


def on_surface(sq: Superquadric, points: np.ndarray) -> np.ndarray:
    return np.abs(sq.inside_outside_pow(points) - 1.0) < 1e-6


def test_a_tilted_line_is_levelled_and_approached_from_straight_above():
    sq = lying_bar(0.015, 0.018, tilt_deg=8.0)
    cands, idx, _ = repaired(sq)
    assert idx.size >= 1
    L = cands.lines
    np.testing.assert_allclose(L.directions[idx] @ TABLE[:3], 0.0, atol=1e-12)
    np.testing.assert_allclose(L.approach0[idx], np.tile([0.0, 0.0, -1.0], (idx.size, 1)))
    assert np.all(L.family[idx] == LEVELLED)
    # Roll 0 (straight down) now clears the table; the contacts lie on the superquadric.
    assert np.all(clear_rolls(cands, idx)[:, 0])
    for sign in (1.0, -1.0):
        contacts = L.centres[idx] + sign * L.half_lengths[idx, None] * L.directions[idx]
        assert np.all(on_surface(sq, contacts))


def test_a_low_line_is_lifted_just_enough():
    # A square bar 2 cm thick: its side line at 10 mm is too low for 9 mm fingertips plus 3 mm.
    sq = lying_bar(0.01, 0.01, eps2=0.1)
    cands, idx, _ = repaired(sq)
    L = cands.lines
    assert idx.size >= 1
    need = GRIPPER.fingertip_overhang_m + CONFIG.table_clearance_m
    np.testing.assert_allclose(L.centres[idx, 2], need, atol=1e-4)
    # Flat sides: the same width as before (to 1 % near the ends, rounded at eps1 = 0.1).
    np.testing.assert_allclose(L.half_lengths[idx], 0.01, rtol=0.01)
    assert np.all(clear_rolls(cands, idx)[:, 0])


def test_a_lift_onto_a_steep_round_side_is_refused_and_pinched_instead():
    # Round bar of radius 8 mm: lifting by ~4 mm puts the contacts where the normal tilts ~30 deg.
    sq = lying_bar(0.008, 0.008)
    no_pinch = GraspConfig(pinch_max_lift_m=0.0)
    cands = synthesize([sq], no_pinch)
    centres = cands.lines.centres.copy()
    idx = level_table_lines(cands, [sq], TABLE, GRIPPER, no_pinch)
    across = np.abs(cands.lines.directions[:, 1]) < 0.5
    assert not np.any(across[idx])
    np.testing.assert_array_equal(cands.lines.centres[across], centres[across])
    # With the pinch, the contacts stay at the bar's equator and only the hand is lifted.
    cands, idx, (centres, _) = repaired(sq)
    L = cands.lines
    assert idx.size >= 1 and np.all(L.family[idx] == PINCHED)
    need = GRIPPER.fingertip_overhang_m + CONFIG.table_clearance_m
    np.testing.assert_allclose(L.centres[idx, 2], need, atol=1e-4)
    # Chords of the round cross-section at the lines' own heights; the equator's is the radius.
    assert np.all(L.half_lengths[idx] <= 0.008 + 1e-9)
    assert np.max(L.half_lengths[idx]) == pytest.approx(0.008, abs=1e-6)
    assert np.all(clear_rolls(cands, idx)[:, 0])
    # A bar too thin for the pads to reach (lift beyond pinch_max_lift_m) gets nothing.
    _, thin, _ = repaired(lying_bar(0.003, 0.003))
    assert thin.size == 0


def test_lines_the_table_does_not_block_are_untouched():
    sq = lying_bar(0.015, 0.1, tilt_deg=8.0)  # high above the table
    cands, idx, (centres, directions) = repaired(sq)
    assert idx.size == 0
    np.testing.assert_array_equal(cands.lines.centres, centres)
    np.testing.assert_array_equal(cands.lines.directions, directions)


def test_steep_lines_are_not_levelled():
    # A box standing on a corner edge, tilted 60 deg: its lines are 60 and 30 deg from the table.
    rot = Rotation.from_euler("y", 60.0, degrees=True).as_matrix()
    sq = Superquadric(0.1, 0.1, [0.012, 0.012, 0.012], rot, [0.5, 0.0, 0.008])
    cands = synthesize([sq], CONFIG)
    before = np.abs(cands.lines.directions @ TABLE[:3])
    idx = level_table_lines(cands, [sq], TABLE, GRIPPER, CONFIG)
    limit = np.sin(np.deg2rad(CONFIG.level_max_angle_deg))
    assert np.any(before > limit) and np.any((before <= limit) & (before > 0.1))
    assert not np.any(np.isin(idx, np.flatnonzero(before > limit)))
    # The line 30 deg from the table is tried, but levelled it meets the box's faces 30 deg off
    # their normals (more than max_tilt_deg): not antipodal, not repaired.
    tried = np.flatnonzero((before <= limit) & (before > 0.1))
    assert not np.any(np.isin(idx, tried))
