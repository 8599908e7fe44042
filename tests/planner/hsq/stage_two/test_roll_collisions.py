"""The exact point-in-gripper test at every roll of a closing line (elimination rules 4, 5)."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.hsq.stage_two.roll_collisions import body_hits
from tests.planner.hsq.stage_two.test_elimination import ROLLS, one_line

ONE = np.array([0])
#: A palm-like box behind the contacts (grasp frame: x closing, y across, z approach).
PALM = np.array([[[[-0.01, -0.01, -0.05], [0.01, 0.01, -0.03]]]])


def _wrapped(angles: np.ndarray) -> np.ndarray:
    return np.abs((angles + np.pi) % (2.0 * np.pi) - np.pi)


def test_a_point_behind_the_line_is_hit_exactly_at_the_rolls_that_put_the_palm_on_it() -> None:
    """At roll phi the point 4 cm along -e1 sits at z = -0.04 cos(phi), y = -0.04 sin(phi):
    inside the palm box while |sin(phi)| <= 1/4 and cos(phi) >= 3/4, i.e. |phi| <= asin(1/4)."""
    line = one_line(0.02)  # along x, e1 = +z at roll 0
    point = np.array([[0.0, 0.0, -0.04]])
    hits = body_hits(point, line, ONE, PALM)
    expected = _wrapped(ROLLS) <= np.arcsin(0.25)
    assert hits.shape == (1, ROLLS.size) and 0 < expected.sum() < ROLLS.size
    np.testing.assert_array_equal(hits[0], expected)


def test_max_points_tolerates_that_many_points_inside() -> None:
    two = np.array([[0.0, 0.0, -0.04], [0.005, 0.0, -0.035]])
    assert body_hits(two, one_line(0.02), ONE, PALM, max_points=1)[0, 0]
    assert not body_hits(two, one_line(0.02), ONE, PALM, max_points=2).any()


def test_with_a_collision_cylinder_only_points_outside_it_are_obstacles() -> None:
    point = np.array([[0.0, 0.0, -0.04]])  # 4 cm from the line
    half_height = np.array([0.05])
    inside_cylinder = body_hits(point, one_line(0.02), ONE, PALM, np.array([0.045]), half_height)
    outside_cylinder = body_hits(point, one_line(0.02), ONE, PALM, np.array([0.035]), half_height)
    assert not inside_cylinder.any() and outside_cylinder[0, 0]


def test_no_points_hit_nothing_and_a_lopsided_box_is_refused() -> None:
    assert not body_hits(np.zeros((0, 3)), one_line(0.02), ONE, PALM).any()
    lopsided = PALM.copy()
    lopsided[0, 0, 0, 1] = -0.02  # y from -2 cm to +1 cm
    with pytest.raises(ValueError, match="symmetric in y"):
        body_hits(np.zeros((1, 3)), one_line(0.02), ONE, lopsided)
