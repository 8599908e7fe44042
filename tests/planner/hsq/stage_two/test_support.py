"""The support rule's measures: cloud spacing, the points a contact needs, what each contact's
cylinder holds and how its plane tilts, and which contacts no camera can see."""

from __future__ import annotations

import numpy as np

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.support import (
    cloud_spacing,
    support_kappa,
    support_stats,
    unobservable_contacts,
)
from tests.planner.hsq.stage_two.test_elimination import one_line, patch

CONFIG = GraspConfig()
ONE = np.array([0])


def test_cloud_spacing_is_the_grid_step_and_infinite_for_one_point() -> None:
    g = np.arange(0.0, 0.1, 0.002)
    grid = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    cloud = np.column_stack([grid, np.zeros(len(grid))])
    assert abs(cloud_spacing(cloud) - 0.002) < 1e-9
    assert cloud_spacing(cloud[:1]) == float("inf")


def test_kappa_is_a_share_of_the_expected_points_never_below_the_floor() -> None:
    fine = 0.001  # pi (1 cm)^2 / (1 mm)^2 = 314 points expected in a cylinder
    expected = np.pi * CONFIG.support_radius_m**2 / fine**2
    assert support_kappa(fine, CONFIG) == int(np.ceil(CONFIG.support_min_fraction * expected))
    assert support_kappa(0.02, CONFIG) == CONFIG.support_min_points  # sparse: the floor


def test_stats_count_the_cylinder_at_each_contact_and_the_plane_tilt() -> None:
    h = 0.03
    face = patch((h, 0, 0), (1, 0, 0), radius=0.008)  # the +d face, square to the line
    deeper = face + np.array([CONFIG.contact_depth_m + 0.005, 0.0, 0.0])  # past the contact
    aside = face + np.array([0.0, CONFIG.support_radius_m + 0.01, 0.0])  # outside the cylinder
    stats = support_stats(np.concatenate([face, deeper, aside]), one_line(h), ONE, CONFIG)
    assert stats.counts.tolist() == [[len(face), 0]]
    assert abs(stats.cos_tilt[0, 0] - 1.0) < 1e-6 and stats.cos_tilt[0, 1] == 0.0
    normal = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)  # the -d face turned 45 degrees
    tilted = patch((-h, 0, 0), -normal, radius=0.008)
    stats = support_stats(tilted, one_line(h), ONE, CONFIG)
    assert stats.counts[0, 0] == 0 and stats.counts[0, 1] > 3
    assert abs(stats.cos_tilt[0, 1] - np.cos(np.pi / 4)) < 1e-6


def test_a_contact_facing_away_from_every_camera_is_unobservable() -> None:
    line = one_line(0.03)  # along x: the +d contact faces +x, the -d contact -x
    right = [(1.0, 0.0, 0.2)]
    assert unobservable_contacts(line, ONE, right, CONFIG).tolist() == [[False, True]]
    both = [(1.0, 0.0, 0.2), (-1.0, 0.0, 0.2)]
    assert unobservable_contacts(line, ONE, both, CONFIG).tolist() == [[False, False]]


def test_above_a_table_a_downward_contact_is_never_called_unobservable() -> None:
    vertical = one_line(0.03, centre=(0, 0, 0.05), direction=(0, 0, 1))
    above = [(0.0, 0.0, 1.0)]
    assert unobservable_contacts(vertical, ONE, above, CONFIG).tolist() == [[False, True]]
    table = np.array([0.0, 0.0, 1.0, 0.0])
    assert unobservable_contacts(vertical, ONE, above, CONFIG, table).tolist() == [[False, False]]
