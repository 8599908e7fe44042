"""Synthesis: principal-axis lines for every superquadric, slides and rotations for prisms,
rectangles and circles (and, with ``slide_all_shapes``, slides for every shape), all antipodal
and in the world frame."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import roll_frames
from hsqbench.planner.hsq.stage_two.synthesis import synthesize
from hsqbench.superquadric.geometry import Superquadric

#: The paper's candidate families only: the tests below check its thresholds.
CONFIG = GraspConfig(slide_all_shapes=False)


def families(sq: Superquadric, config: GraspConfig = CONFIG) -> dict[str, int]:
    lines = synthesize([sq], config).lines
    names, counts = np.unique(lines.family, return_counts=True)
    return dict(zip(names.tolist(), counts.tolist(), strict=True))


def test_ellipsoid_gets_its_three_axes_rolled_every_10_degrees() -> None:
    rot = Rotation.from_euler("xyz", [0.3, -0.5, 1.1]).as_matrix()
    sq = Superquadric(1.0, 1.0, [0.03, 0.02, 0.05], rot, [0.1, -0.2, 0.3])
    cands = synthesize([sq], CONFIG)
    lines = cands.lines
    assert len(lines) == 3 and len(cands) == 3 * 36
    np.testing.assert_allclose(lines.centres, np.tile(sq.translation, (3, 1)))
    np.testing.assert_allclose(np.abs(lines.directions @ rot), np.eye(3), atol=1e-12)
    np.testing.assert_allclose(lines.half_lengths, sq.scale)
    np.testing.assert_allclose(np.diff(cands.roll_angles), np.deg2rad(10.0))


def test_cuboid_slides_every_15_mm_inside_its_faces() -> None:
    sq = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])
    lines = synthesize([sq], CONFIG).lines
    slides = lines.family == "slide"
    assert np.count_nonzero(slides) > 20
    # Offsets are multiples of 15 mm, strictly inside the superquadric, perpendicular to the line.
    offset = lines.centres[slides]
    np.testing.assert_allclose(offset / 0.015, np.round(offset / 0.015), atol=1e-9)
    assert np.all(np.abs(offset) < sq.scale)
    np.testing.assert_allclose(np.einsum("ij,ij->i", offset, lines.directions[slides]), 0.0)
    # lambda_x moves over the y-z face grid, lambda_z over the base grid.
    along_x = slides & (lines.axis == 0)
    assert set(np.round(lines.centres[along_x, 2], 3)) >= {-0.045, -0.015, 0.0, 0.015, 0.045}
    assert set(np.round(lines.centres[along_x, 1], 3)) == {-0.015, 0.0, 0.015}
    along_z = slides & (lines.axis == 2)
    assert np.all(lines.centres[along_z, 2] == 0.0) and np.count_nonzero(along_z) == 8


def test_cylinder_rotates_about_z_every_pi_over_8_and_slides() -> None:
    sq = Superquadric(0.1, 1.0, [0.03, 0.03, 0.05])
    lines = synthesize([sq], CONFIG).lines
    counts = families(sq)
    assert counts["rotate"] == 6  # 22.5 deg steps in [0, 180), without 0 and 90 (the axes)
    assert counts["rotate+slide"] == 6 * 6  # and at each of the six non-zero heights
    in_plane = lines.family != "axis"
    horizontal = np.abs(lines.directions[:, 2]) < 1e-12
    angles = np.degrees(
        np.arctan2(lines.directions[horizontal, 1], lines.directions[horizontal, 0])
    )
    steps = np.round(np.mod(angles, 180.0) / 22.5, 6)
    assert set(steps) == set(range(8))
    # Every rotated line reaches the side wall: half length = radius.
    np.testing.assert_allclose(lines.half_lengths[in_plane & horizontal], 0.03, rtol=1e-2)


@pytest.mark.parametrize(
    ("eps1", "eps2", "scale", "expected"),
    [
        (1.0, 1.0, [0.03, 0.03, 0.03], {"axis", "rotate"}),  # sphere: round section only
        (0.6, 0.6, [0.03, 0.02, 0.05], {"axis"}),  # rounded block: no flat family
        (0.4, 1.6, [0.03, 0.02, 0.05], {"axis", "slide"}),  # prism (eps1 -> 0) only
        (1.0, 0.3, [0.03, 0.02, 0.05], {"axis", "slide"}),  # rectangle (eps2 -> 0) only
        (0.1, 1.0, [0.03, 0.027, 0.05], {"axis", "slide", "rotate", "rotate+slide"}),
        (0.1, 1.0, [0.03, 0.02, 0.05], {"axis", "slide"}),  # ax != ay: not circular
    ],
)
def test_families_follow_the_thresholds(eps1, eps2, scale, expected) -> None:
    assert set(families(Superquadric(eps1, eps2, scale))) == expected


def test_rectangle_slides_only_in_the_cross_section() -> None:
    sq = Superquadric(1.0, 0.2, [0.03, 0.02, 0.05])
    lines = synthesize([sq], CONFIG).lines
    moved = lines.family == "slide"
    # lambda_x slides along y, lambda_y along x, never along z (eps1 is not flat).
    assert np.all(lines.centres[moved, 2] == 0.0)
    np.testing.assert_allclose(lines.centres[moved & (lines.axis == 0), 0], 0.0)
    np.testing.assert_allclose(lines.centres[moved & (lines.axis == 1), 1], 0.0)


def test_moved_lines_are_antipodal_within_the_tilt_limit() -> None:
    """Contacts lie on the surface with normals within max_tilt_deg of the line, both sides."""
    for sq in (
        Superquadric(0.45, 0.1, [0.03, 0.02, 0.05]),
        Superquadric(0.1, 1.15, [0.03, 0.028, 0.04]),
    ):
        lines = synthesize([sq], CONFIG).lines
        for sign in (1.0, -1.0):
            contact = lines.centres + sign * lines.half_lengths[:, None] * lines.directions
            np.testing.assert_allclose(sq.inside_outside_pow(contact), 1.0, atol=1e-6)
            cos = sign * np.einsum("ij,ij->i", sq.normals(contact), lines.directions)
            assert np.all(cos >= np.cos(np.deg2rad(CONFIG.max_tilt_deg)) - 1e-6)


def test_tilt_limit_trims_slides_near_rounded_edges() -> None:
    rounded = Superquadric(0.45, 0.1, [0.03, 0.02, 0.05])
    sharp = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])
    z_round = np.abs(synthesize([rounded], CONFIG).lines.centres[:, 2])
    z_sharp = np.abs(synthesize([sharp], CONFIG).lines.centres[:, 2])
    assert z_sharp.max() == pytest.approx(0.045)
    assert z_round.max() < z_sharp.max()
    loose = GraspConfig(max_tilt_deg=60.0)
    assert np.abs(synthesize([rounded], loose).lines.centres[:, 2]).max() == pytest.approx(0.045)


def test_lines_follow_the_superquadric_pose_and_name_their_source() -> None:
    local = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])
    rot = Rotation.from_rotvec([0.2, 0.4, -0.7]).as_matrix()
    moved = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05], rot, [0.5, 0.1, 0.2])
    a = synthesize([local, moved], CONFIG).lines
    n = len(a) // 2
    assert np.all(a.source[:n] == 0) and np.all(a.source[n:] == 1)
    np.testing.assert_allclose(a.centres[n:], a.centres[:n] @ rot.T + moved.translation)
    np.testing.assert_allclose(a.directions[n:], a.directions[:n] @ rot.T, atol=1e-12)
    np.testing.assert_allclose(a.half_lengths[n:], a.half_lengths[:n])
    frames = roll_frames(a.directions, a.approach0, np.deg2rad([0.0, 10.0, 200.0]))
    np.testing.assert_allclose(np.linalg.det(frames), 1.0)


def test_no_superquadric_gives_no_candidates() -> None:
    cands = synthesize([], CONFIG)
    assert len(cands) == 0 and len(cands.lines) == 0


def test_slide_all_shapes_slides_a_rounded_bottle_where_it_stays_antipodal() -> None:
    # A bottle-like body: rounded (eps 0.8), 6 cm thick, 10 cm wide, 20 cm tall.
    sq = Superquadric(0.8, 0.8, [0.03, 0.05, 0.1])
    assert set(families(sq)) == {"axis"}
    lines = synthesize([sq], GraspConfig(slide_all_shapes=True)).lines
    across = (lines.family == "slide") & (np.abs(lines.directions[:, 0]) > 0.99)
    # Lines across the thickness slide up and down the body and toward its edges ...
    assert np.ptp(lines.centres[across, 2]) >= 0.1
    assert np.max(np.abs(lines.centres[across, 1])) >= 0.015
    # ... and every one meets the surface within max_tilt_deg of its direction at both ends.
    for sign in (1.0, -1.0):
        contact = lines.centres + sign * lines.half_lengths[:, None] * lines.directions
        grad = np.array(
            [sq.inside_outside_pow(c[None] + e * 1e-7)[0] for c in contact for e in np.eye(3)]
        )
        grad = grad.reshape(-1, 3) - sq.inside_outside_pow(contact)[:, None]
        cos = sign * np.einsum("ij,ij->i", grad, lines.directions) / np.linalg.norm(grad, axis=1)
        assert np.all(cos >= np.cos(np.deg2rad(CONFIG.max_tilt_deg)) - 1e-3)
    # Near the rounded top and bottom the surface tilts away: no slide reaches the very ends.
    assert np.max(np.abs(lines.centres[across, 2])) < 0.1


def test_parts_thinner_than_the_noise_get_no_lines() -> None:
    face = Superquadric(1.0, 1.0, [0.002, 0.015, 0.02])  # a fit at stage one's 2 mm floor
    shaft = Superquadric(1.0, 1.0, [0.003, 0.003, 0.03])  # a 6 mm screwdriver shaft
    cands = synthesize([face, shaft], CONFIG)
    assert set(cands.lines.source.tolist()) == {1}
    assert len(synthesize([face], GraspConfig(min_part_scale_m=0.0))) > 0
