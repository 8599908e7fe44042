"""The real Contact-GraspNet network in the harness (runs whenever the ``learned`` extra is
installed; ``make test`` installs it): grasps on a box seen by the harness's two cameras."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.learned import network
from tests.shapes import Box, visible_mask

pytestmark = pytest.mark.skipif(
    not network.available(),
    reason="the learned extra is not installed (pip install -e '.[learned]' && make learned)",
)

#: The harness's cameras (configs/scene.yaml) and table (z = 0 here).
CAMERAS = np.array([[0.62, 0.78, 0.55], [0.62, -0.78, 0.55]])
TABLE = (0.0, 0.0, 1.0, 0.0)
#: A 6 x 10 x 8 cm box on the table: 6 cm fits the 8 cm opening, 10 cm does not.
BOX = Box((0.03, 0.05, 0.04), center=np.array([0.5, 0.0, 0.04]))


def box_cloud(seed: int = 0) -> np.ndarray:
    """The box as the harness sees it: both cameras' visible points, 2 mm apart, 1 mm noise."""
    rng = np.random.default_rng(seed)
    points, normals = BOX.sample_surface(round(BOX.area() / 0.002**2), rng)
    seen = np.zeros(len(points), dtype=bool)
    for camera in CAMERAS:
        seen |= visible_mask(points, normals, camera)
    seen &= points[:, 2] > 0.002  # the table hides the bottom face
    return points[seen] + rng.normal(scale=0.001, size=(int(seen.sum()), 3))


def context(seed: int = 0) -> PlanningContext:
    return PlanningContext(support_plane=TABLE, seed=seed, camera_positions=CAMERAS)


@pytest.fixture(scope="module")
def planner():
    from hsqbench.planner.registry import get_planner

    return get_planner("contact-graspnet")


@pytest.fixture(scope="module")
def result(planner):
    return planner.plan(box_cloud(), context())


def face_of(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(axis (M,), distance to the nearest face (M,)) of points in the box's frame."""
    local = points - BOX.center
    h = np.asarray(BOX.half_extents)
    gap = np.abs(np.abs(local) - h)
    return np.argmin(gap, axis=1), np.min(gap, axis=1)


def test_top_grasps_close_on_opposite_faces_of_the_box(result):
    assert result.planner == "contact-graspnet"
    assert len(result.grasps) >= 10, result.reason
    top = [result.grasps[i] for i in range(10)]
    scores = [g.score for g in top]
    assert scores == sorted(scores, reverse=True)
    assert all(0.5 <= s <= 1.0 for s in scores)
    n_opposite = 0
    for grasp in top:
        a, b = grasp.contacts()
        axis, gap = face_of(np.stack([a, b]))
        local = np.stack([a, b]) - BOX.center
        closing_axis = int(np.argmax(np.abs(grasp.closing_axis)))
        opposite = (
            axis[0] == axis[1] == closing_axis
            and np.sign(local[0, closing_axis]) != np.sign(local[1, closing_axis])
            and np.all(gap < 0.01)  # both fingers within 1 cm of the face they press on
            and abs(grasp.closing_axis[closing_axis]) > np.cos(np.deg2rad(20.0))
        )
        n_opposite += bool(opposite)
    # Only the 6 cm and 8 cm pairs of faces fit the 8 cm opening; nearly all top grasps use one.
    assert n_opposite >= 8, n_opposite


def test_grasps_approach_from_outside_the_box(result):
    for grasp in [result.grasps[i] for i in range(20)]:
        palm = grasp.position - 0.1034 * grasp.approach_axis
        local = np.abs(palm - BOX.center)
        assert np.any(local > np.asarray(BOX.half_extents) + 0.01)  # the palm is outside
        assert palm[2] > 0.0  # above the table


def test_same_seed_same_grasps_and_timings_reported(planner, result):
    again = planner.plan(box_cloud(), context())
    assert len(again.grasps) == len(result.grasps)
    for i in (0, len(result.grasps) // 2, len(result.grasps) - 1):
        np.testing.assert_array_equal(again.grasps[i].position, result.grasps[i].position)
        assert again.grasps[i].score == result.grasps[i].score
    other = planner.plan(box_cloud(), context(seed=7))
    assert not np.array_equal(other.grasps[0].position, result.grasps[0].position)
    assert result.timings["network"] > 0 and result.timings["total"] >= result.timings["network"]


def test_elimination_variant_keeps_only_grasps_that_pass_the_rules(result):
    from hsqbench.planner.registry import get_planner

    elim = get_planner("contact-graspnet-elim").plan(box_cloud(), context())
    assert elim.planner == "contact-graspnet-elim"
    assert elim.remaining["synthesised"] == len(result.grasps)
    assert 0 < len(elim.grasps) <= len(result.grasps)
    assert len(elim.grasps) == elim.candidates.counts_by_reason()["kept"]
    assert sum(elim.removed_by.values()) == len(result.grasps) - len(elim.grasps)
    kept = np.flatnonzero(elim.candidates.kept)
    assert set(elim.grasps.indices) == set(kept)
