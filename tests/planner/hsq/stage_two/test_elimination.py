"""Elimination rules: each removes a constructed bad candidate and keeps a good one; the exact
roll-arc collision test agrees with transforming every point into every candidate's frame."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet, ClosingLines, roll_frames
from hsqbench.planner.hsq.stage_two.elimination import (
    approach_openings,
    body_hits,
    duplicate_lines,
    eliminate,
    line_boxes,
    support_kappa,
)
from hsqbench.planner.hsq.stage_two.synthesis import roll_angles

GRIPPER = GripperModel()
CONFIG = GraspConfig()
ROLLS = roll_angles(CONFIG)


def one_line(half_length: float, centre=(0.0, 0.0, 0.0), direction=(1.0, 0.0, 0.0)) -> CandidateSet:
    """A single closing line; at roll 0 the approach is +z, so the palm sits at -z."""
    d = np.asarray(direction, dtype=float)
    e1 = np.array([0.0, 0.0, 1.0]) if abs(d[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    lines = ClosingLines(
        centres=np.asarray(centre, dtype=float)[None],
        directions=d[None],
        approach0=e1[None],
        half_lengths=np.array([half_length]),
        source=np.zeros(1, dtype=np.int64),
        axis=np.zeros(1, dtype=np.int64),
        family=np.array(["axis"]),
    )
    return CandidateSet(lines, ROLLS)


def patch(center, normal, radius=0.012, spacing=0.002) -> np.ndarray:
    """A flat disc of points (a face seen by a camera) around ``center`` facing ``normal``."""
    normal = np.asarray(normal, dtype=float)
    helper = np.array([0.0, 0.0, 1.0]) if abs(normal[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    a = np.cross(normal, helper)
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    g = np.arange(-radius, radius + 1e-9, spacing)
    ga, gb = np.meshgrid(g, g)
    keep = ga**2 + gb**2 <= radius**2
    return np.asarray(center) + ga[keep, None] * a + gb[keep, None] * b


def two_faces(half_width: float) -> np.ndarray:
    """The two faces a line of half length ``half_width`` along x grips."""
    return np.concatenate(
        [patch((half_width, 0, 0), (1, 0, 0)), patch((-half_width, 0, 0), (-1, 0, 0))]
    )


def reasons(cands: CandidateSet) -> np.ndarray:
    return cands.rejected_by.reshape(len(cands.lines), cands.n_roll)[0]


def test_width_removes_lines_wider_than_the_opening() -> None:
    for half, expect in ((0.03, ""), (0.039, "width"), (0.05, "width")):
        cands = one_line(half)
        eliminate(cands, two_faces(half), GRIPPER, CONFIG)
        assert set(reasons(cands)) == {expect} if expect else "width" not in set(reasons(cands))


def test_support_needs_points_at_both_contacts() -> None:
    good = one_line(0.02)
    eliminate(good, two_faces(0.02), GRIPPER, CONFIG)
    assert np.all(reasons(good) == "")
    # The -x face is missing (unseen or not there): nothing to push against on that side.
    bad = one_line(0.02)
    eliminate(bad, patch((0.02, 0, 0), (1, 0, 0)), GRIPPER, CONFIG)
    assert np.all(reasons(bad) == "support")
    # A face 15 mm beyond the modelled contact is too far from it to count.
    far = one_line(0.02)
    cloud = np.concatenate([patch((0.02, 0, 0), (1, 0, 0)), patch((-0.035, 0, 0), (-1, 0, 0))])
    eliminate(far, cloud, GRIPPER, CONFIG)
    assert np.all(reasons(far) == "support")


def test_support_is_not_asked_of_a_contact_no_camera_sees() -> None:
    one_face = patch((0.02, 0, 0), (1, 0, 0))
    # Cameras on the +x side and above: the -x face is more than 75 deg from both.
    behind = np.array([[0.6, 0.3, 0.3], [0.6, -0.3, 0.3]])
    kept = one_line(0.02)
    eliminate(kept, one_face, GRIPPER, CONFIG, camera_positions=behind)
    assert np.all(reasons(kept) == "")
    # A camera facing the -x contact could have seen it: its empty disc means nothing is there.
    facing = np.array([[0.6, 0.3, 0.3], [-0.6, 0.0, 0.1]])
    gone = one_line(0.02)
    eliminate(gone, one_face, GRIPPER, CONFIG, camera_positions=facing)
    assert np.all(reasons(gone) == "support")
    # The seen contact must still show support: no evidence at all is no grasp.
    empty = one_line(0.02)
    far_cloud = patch((0.0, 0.1, 0), (0, 1, 0))
    eliminate(empty, far_cloud, GRIPPER, CONFIG, camera_positions=behind)
    assert np.all(reasons(empty) == "support")
    # A downward contact is never waived when the table is known: cameras above see no
    # downward face, so a missing one may be the inside of the object. A vertical line whose
    # top face is seen, its bottom not:
    top_face = patch((0.0, 0.0, 0.02), (0, 0, 1))
    vertical = one_line(0.02, direction=(0.0, 0.0, 1.0))
    eliminate(vertical, top_face, GRIPPER, CONFIG, camera_positions=behind)
    assert "" in set(reasons(vertical))  # without the table, the bottom counts as unseen
    vertical = one_line(0.02, direction=(0.0, 0.0, 1.0))
    table = np.array([0.0, 0.0, 1.0, 0.5])  # far below: only the direction matters here
    eliminate(vertical, top_face, GRIPPER, CONFIG, table, camera_positions=behind)
    assert np.all(reasons(vertical) == "support")
    # Neither contact visible: still no grasp.
    above = np.array([[0.0, 0.0, 1.0]])
    blind = one_line(0.02)
    eliminate(blind, far_cloud, GRIPPER, CONFIG, camera_positions=above)
    assert np.all(reasons(blind) == "support")


def test_support_threshold_follows_cloud_density() -> None:
    dense, sparse = support_kappa(0.001, CONFIG), support_kappa(0.006, CONFIG)
    assert dense > sparse >= CONFIG.support_min_points
    # A tenth of a disc of radius 1 cm at 1 mm spacing: about 0.1 * 314 points.
    assert dense == pytest.approx(0.1 * np.pi * 100, rel=0.02)


def test_table_removes_rolls_whose_gripper_enters_the_plane() -> None:
    # Closing along x at 2 cm above a table z = 0: approaching from above is fine, from the side
    # the palm (6.3 cm thick) dips into the table, from below the whole hand is under it.
    cands = one_line(0.02, centre=(0.0, 0.0, 0.02))
    cloud = two_faces(0.02) + np.array([0.0, 0.0, 0.02])
    eliminate(cands, cloud, GRIPPER, CONFIG, support_plane=np.array([0.0, 0.0, 1.0, 0.0]))
    frames = roll_frames(cands.lines.directions, cands.lines.approach0, ROLLS)[0]
    approach_z = frames[:, 2, 2]
    r = reasons(cands)
    assert np.all(r[approach_z < -0.99] == "")  # straight down
    assert np.all(r[np.abs(approach_z) < 0.1] == "table")  # sideways: the palm dips in
    assert np.all(r[approach_z > 0.5] == "table")  # from below
    # Without the plane, nothing is removed.
    free = one_line(0.02, centre=(0.0, 0.0, 0.02))
    eliminate(free, cloud, GRIPPER, CONFIG)
    assert np.all(reasons(free) == "")


def test_paper_collision_removes_rolls_whose_palm_meets_the_object() -> None:
    # An object part 6 cm below the closing line, between the end planes: beyond the jaw's reach
    # l_j = 3.74 cm. The palm meets it when approaching from above (palm at -approach = ...).
    obstacle = patch((0.0, 0.0, -0.06), (0, 0, 1), radius=0.01)
    cands = one_line(0.02)
    eliminate(cands, np.concatenate([two_faces(0.02), obstacle]), GRIPPER, CONFIG)
    frames = roll_frames(cands.lines.directions, cands.lines.approach0, ROLLS)[0]
    approach_z = frames[:, 2, 2]
    r = reasons(cands)
    # Roll 0 approaches along +z, so the palm is at -z, on the obstacle: removed.
    assert r[np.argmax(approach_z)] == "collision"
    # Approaching from -z puts the palm on the other side: kept.
    assert r[np.argmin(approach_z)] == ""
    # Closer than l_j the part sits between the fingers: not an obstacle.
    near = one_line(0.02)
    inner = patch((0.0, 0.0, -0.03), (0, 0, 1), radius=0.01)
    eliminate(near, np.concatenate([two_faces(0.02), inner]), GRIPPER, CONFIG)
    assert np.all(reasons(near) == "")


def test_sweep_removes_poses_whose_fingers_hit_points_beyond_the_contacts() -> None:
    # A wall 5 cm from P_G along the closing axis, beyond the contact at 2 cm: outside the paper's
    # end planes, but exactly where the open finger (3 to 5.6 cm, opening 2 cm + 2 x 1 cm) goes.
    wall = patch((0.05, 0.0, 0.0), (1, 0, 0), radius=0.02)
    cands = one_line(0.02)
    eliminate(cands, np.concatenate([two_faces(0.02), wall]), GRIPPER, CONFIG)
    assert set(reasons(cands)) == {"sweep"}
    # The same wall 12 cm away is past the palm's half width (10.2 cm): kept.
    far_wall = patch((0.12, 0.0, 0.0), (1, 0, 0), radius=0.02)
    ok = one_line(0.02)
    eliminate(ok, np.concatenate([two_faces(0.02), far_wall]), GRIPPER, CONFIG)
    assert np.all(reasons(ok) == "")


def test_obstacle_tolerance_ignores_two_strays_but_not_a_wall() -> None:
    tolerant = GraspConfig(max_obstacle_points=2)
    # Two stray points in the +x finger's volume (3 to 5.6 cm along the line) at every roll.
    strays = np.array([[0.045, 0.0, 0.0], [0.05, 0.0, 0.0]])
    cloud = np.concatenate([two_faces(0.02), strays])
    strict = one_line(0.02)
    eliminate(strict, cloud, GRIPPER, CONFIG)
    assert set(reasons(strict)) == {"sweep"}
    lenient = one_line(0.02)
    eliminate(lenient, cloud, GRIPPER, tolerant)
    assert np.all(reasons(lenient) == "")
    # A wall there has many points in the finger: removed all the same.
    wall = patch((0.05, 0.0, 0.0), (1, 0, 0), radius=0.02)
    walled = one_line(0.02)
    eliminate(walled, np.concatenate([two_faces(0.02), wall]), GRIPPER, tolerant)
    assert set(reasons(walled)) == {"sweep"}
    # The paper's collision rule counts the same way: 2 points behind the palm face are
    # tolerated, a third is not.
    palm = np.array([[0.0, 0.0, -0.05], [0.005, 0.0, -0.05], [0.0, 0.005, -0.05]])
    for n, expect in ((2, ""), (3, "collision")):
        cands = one_line(0.02)
        eliminate(cands, np.concatenate([two_faces(0.02), palm[:n]]), GRIPPER, tolerant)
        assert reasons(cands)[0] == expect


def test_sweep_catches_points_behind_the_palm() -> None:
    # A point 15 cm behind P_G along -z: behind the palm (ends at 3.74 + 9.19 = 12.9 cm) but
    # inside the 5 cm approach sweep. Only the roll whose palm points at it is removed.
    point = patch((0.0, 0.0, -0.15), (0, 0, 1), radius=0.004)
    cands = one_line(0.02)
    eliminate(cands, np.concatenate([two_faces(0.02), point]), GRIPPER, CONFIG)
    frames = roll_frames(cands.lines.directions, cands.lines.approach0, ROLLS)[0]
    r = reasons(cands)
    assert r[np.argmax(frames[:, 2, 2])] == "sweep"
    assert r[np.argmin(frames[:, 2, 2])] == ""


def brute_force_hits(
    points, cands, boxes, radius=None, half_height=None, max_points: int = 0
) -> np.ndarray:
    """Every point in every candidate's grasp frame, tested against each line's boxes; a
    candidate is hit when more than ``max_points`` obstacle points lie in its boxes."""
    L = cands.lines
    frames = roll_frames(L.directions, L.approach0, cands.roll_angles)  # (L, R, 3, 3)
    rel = points[None] - L.centres[:, None]  # (L, M, 3)
    local = np.einsum("lmk,lrkj->lrmj", rel, frames)  # (L, R, M, 3)
    obstacle = np.ones(rel.shape[:2], dtype=bool)
    if radius is not None:
        s = np.einsum("lmk,lk->lm", rel, L.directions)
        r2 = np.einsum("lmk,lmk->lm", rel, rel) - s * s
        obstacle = (np.abs(s) <= half_height[:, None]) & (r2 > radius[:, None] ** 2)
    inside = np.zeros(local.shape[:3], dtype=bool)
    for b in range(boxes.shape[1]):
        lo = boxes[:, b, 0][:, None, None, :]
        hi = boxes[:, b, 1][:, None, None, :]
        inside |= np.all((local >= lo) & (local <= hi), axis=-1)
    return np.sum(inside & obstacle[:, None, :], axis=2) > max_points


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_arc_collision_test_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n_lines = 12
    d = rng.normal(size=(n_lines, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    e1 = np.cross(d, rng.normal(size=(n_lines, 3)))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    lines = ClosingLines(
        centres=rng.uniform(-0.05, 0.05, size=(n_lines, 3)),
        directions=d,
        approach0=e1,
        half_lengths=rng.uniform(0.005, 0.04, size=n_lines),
        source=np.zeros(n_lines, dtype=np.int64),
        axis=np.zeros(n_lines, dtype=np.int64),
        family=np.array(["axis"] * n_lines),
    )
    cands = CandidateSet(lines, ROLLS)
    points = rng.uniform(-0.2, 0.2, size=(40, 3))
    index = np.arange(n_lines)
    openings = approach_openings(lines.half_lengths, GRIPPER, CONFIG)
    assert np.ptp(openings) > 0.01  # the fingers really differ from line to line
    for extension in (0.0, 0.05):
        # Each line's boxes built one by one, independently of line_boxes.
        boxes = np.array([GRIPPER.boxes(opening_m=o, palm_extension_m=extension) for o in openings])
        np.testing.assert_allclose(line_boxes(GRIPPER, openings, extension), boxes)
        fast = body_hits(points, cands, index, boxes)
        slow = brute_force_hits(points, cands, boxes)
        assert 0 < slow.sum() < slow.size  # a meaningful mix of hits and misses
        np.testing.assert_array_equal(fast, slow)
    boxes = line_boxes(GRIPPER, openings)
    radius = np.full(n_lines, GRIPPER.jaw_length_m)
    half = np.minimum(lines.half_lengths, GRIPPER.max_opening_m / 2)
    fast = body_hits(points, cands, index, boxes, radius, half)
    slow = brute_force_hits(points, cands, boxes, radius, half)
    assert slow.sum() > 0
    np.testing.assert_array_equal(fast, slow)
    # Counting: more than k points inside, for a dense cloud where many candidates hold several.
    dense = rng.uniform(-0.2, 0.2, size=(200, 3))
    swept = line_boxes(GRIPPER, openings, 0.05)
    for k in (1, 3):
        fast = body_hits(dense, cands, index, swept, max_points=k)
        slow = brute_force_hits(dense, cands, swept, max_points=k)
        assert 0 < slow.sum() < slow.size
        np.testing.assert_array_equal(fast, slow)


def test_approach_opening_clears_the_contacts_within_the_stroke() -> None:
    half = np.array([0.005, 0.02, 0.035])
    np.testing.assert_allclose(approach_openings(half, GRIPPER, CONFIG), [0.03, 0.06, 0.08])
    cands = one_line(0.02)
    eliminate(cands, two_faces(0.02), GRIPPER, CONFIG)
    grasp = cands.grasp(0)
    assert grasp.approach_width == pytest.approx(0.06) and grasp.width == pytest.approx(0.04)


def test_counts_follow_the_rule_order() -> None:
    # Two lines: one too wide, one fine but with its palm side blocked at roll 0.
    cands = one_line(0.02)
    wide = one_line(0.05)
    both = CandidateSet(ClosingLines.concatenate([cands.lines, wide.lines]), ROLLS)
    obstacle = patch((0.0, 0.0, -0.06), (0, 0, 1), radius=0.01)
    report = eliminate(both, np.concatenate([two_faces(0.02), obstacle]), GRIPPER, CONFIG)
    n = len(ROLLS)
    assert report.remaining["synthesised"] == 2 * n
    assert report.remaining["duplicate"] == 2 * n
    assert report.remaining["width"] == n
    assert report.remaining["support"] == n
    counts = both.counts_by_reason()
    assert counts["width"] == n
    assert counts["collision"] == n - report.remaining["collision"]
    assert counts["kept"] == report.remaining["sweep"]


def test_duplicate_lines_keep_the_best_fitting_copy() -> None:
    base = one_line(0.02).lines
    near = one_line(0.021, centre=(0.001, -0.001, 0.0), direction=(-1.0, 0.02, 0.0)).lines
    other = one_line(0.02, centre=(0.0, 0.01, 0.0)).lines  # 1 cm away: a different line
    turned = one_line(0.02, direction=(np.cos(0.1), np.sin(0.1), 0.0)).lines  # 5.7 deg off
    lines = ClosingLines.concatenate([base, near, other, turned])
    dup = duplicate_lines(lines, np.array([0.5, 0.9, 0.5, 0.5]), CONFIG)
    np.testing.assert_array_equal(dup, [True, False, False, False])
    # Equal priority: the first copy stays.
    dup = duplicate_lines(lines, np.zeros(4), CONFIG)
    np.testing.assert_array_equal(dup, [False, True, False, False])
    # In elimination the copy is marked and the rules see one line.
    cands = CandidateSet(lines, ROLLS)
    eliminate(cands, two_faces(0.02), GRIPPER, CONFIG, line_priority=np.array([0.5, 0.9, 0.5, 0.5]))
    per_line = cands.rejected_by.reshape(4, -1)
    assert set(per_line[0]) == {"duplicate"} and "duplicate" not in set(per_line[1])


def test_where_rule_6_runs_the_facing_test_does_not() -> None:
    # The +x contact sees an edge (a surface 60 deg from the line), the -x one a face.
    slanted = patch((0.02, 0, 0), (np.cos(np.pi / 3), 0.0, np.sin(np.pi / 3)), radius=0.009)
    cloud = np.concatenate([slanted, patch((-0.02, 0, 0), (-1, 0, 0))])
    strict = one_line(0.02)
    eliminate(strict, cloud, GRIPPER, CONFIG)
    assert set(reasons(strict)) == {"support"}
    modelled = one_line(0.02)
    eliminate(modelled, cloud, GRIPPER, CONFIG, body_points=np.zeros((0, 3)))
    assert set(reasons(modelled)) == {""}
    off = one_line(0.02)
    cfg = dataclasses.replace(CONFIG, body_rule=False)
    eliminate(off, cloud, GRIPPER, cfg, body_points=np.zeros((0, 3)))
    assert set(reasons(off)) == {"support"}
