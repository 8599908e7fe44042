"""Pose geometry of the grasp motion (hsqbench.sim.trial.geometry): pure, no scene."""

from __future__ import annotations

import numpy as np

from hsqbench.sim.ik import Pose
from hsqbench.sim.trial.geometry import carry_pose, first_pose, lift_height, rot_z

DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])


def test_lift_height_clears_the_bin_walls_or_takes_the_minimum():
    assert np.isclose(lift_height(0.1, 0.9, 0.04, 0.75), 0.19)
    assert lift_height(0.3, 0.9, 0.04, 0.75) == 0.3


def test_carry_pose_puts_the_held_point_over_the_bin_centre():
    bin_c = np.array([0.0, 0.6])
    lifted = Pose(np.array([0.52, 0.03, 0.4]), rot_z(0.3) @ DOWN)
    held = np.array([0.5, 0.0])
    carry, yaw = carry_pose(bin_c, lifted, held)
    turned = rot_z(yaw)[:2, :2] @ held
    assert np.allclose(turned, bin_c / np.linalg.norm(bin_c) * np.linalg.norm(held))
    # The TCP keeps its offset to the held point, turned with the hand; same height and tilt.
    offset = carry.position[:2] - bin_c
    assert np.allclose(offset, rot_z(yaw)[:2, :2] @ (lifted.position[:2] - held))
    assert carry.position[2] == lifted.position[2]
    assert np.allclose(carry.rotation, rot_z(yaw) @ lifted.rotation)
    assert -np.pi <= yaw <= np.pi
    _, back = carry_pose(np.array([0.0, -0.6]), lifted, np.array([-0.5, 0.01]))
    assert -np.pi <= back <= np.pi


def test_first_pose_hovers_above_a_low_pregrasp():
    pose = Pose(np.array([0.5, 0.0, 0.05]), DOWN)
    box = (np.array([-0.1, -0.02, -0.1]), np.array([0.1, 0.02, 0.0]))  # the hand, TCP frame
    first, pre = first_pose(pose, 0.1, box, clear_z=0.3)
    assert np.allclose(pre.position, [0.5, 0.0, 0.15])
    # Approach down: the hand's lowest point is the TCP-frame z = 0 face, at the TCP height.
    assert np.allclose(first.position, [0.5, 0.0, 0.3])
    high, pre2 = first_pose(pose, 0.1, box, clear_z=0.1)
    assert high is pre2
