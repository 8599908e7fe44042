"""Grasp ordering and de-duplication (hsqbench.sim.trial.ordering): pure functions, no scene."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from hsqbench.sim.trial.ordering import distinct_in_order, execution_order, grasp_key

DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
# Approach along -x: toward the robot at the origin from a grasp at +x (the hard direction).
TOWARD = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])


def _g(position, rotation, score):
    return SimpleNamespace(position=np.asarray(position, float), rotation=rotation, score=score)


def test_order_is_by_score_then_by_the_easy_approach():
    grasps = [
        _g([0.5, 0.0, 0.1], TOWARD, 0.9),
        _g([0.5, 0.0, 0.1], DOWN, 0.9),
        _g([0.5, 0.0, 0.1], DOWN, 0.95),
    ]
    assert execution_order(grasps, 8) == [2, 1, 0]
    assert execution_order(grasps, 2) == [1, 0]  # only the first `window` ranks


def test_key_ignores_the_closing_sign_and_sub_millimetre_noise():
    a = _g([0.5, 0.1, 0.1], DOWN, 1.0)
    flipped = DOWN * np.array([-1.0, -1.0, 1.0])  # closing and y axes reversed, same approach
    assert grasp_key(a) == grasp_key(_g([0.5001, 0.1, 0.1], flipped, 0.5))
    assert grasp_key(a) != grasp_key(_g([0.503, 0.1, 0.1], DOWN, 1.0))
    assert grasp_key(a) != grasp_key(_g([0.5, 0.1, 0.1], TOWARD, 1.0))


def test_distinct_in_order_skips_twins_and_stops_at_the_cap():
    grasps = [_g([0.5, 0.01 * k, 0.1], DOWN, 1.0 - 0.01 * k) for k in range(3)]
    grasps.insert(1, _g([0.5, 0.0, 0.1], DOWN, 0.995))  # a twin of rank 0
    grasps.append(_g([0.6, 0.0, 0.1], DOWN, 0.5))
    assert distinct_in_order(grasps, 10) == [0, 2, 3, 4]
    assert distinct_in_order(grasps, 2) == [0, 2]
