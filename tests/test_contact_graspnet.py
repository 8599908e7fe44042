"""The real Contact-GraspNet network in the harness (runs whenever the ``learned`` extra is
installed; ``make test`` installs it): grasps on a box seen by the harness's two cameras."""

from __future__ import annotations

import dataclasses

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
#: A 10 x 6 x 8 cm box on the table: across y (6 cm, the faces the two cameras see) it fits the
#: 8 cm opening; across x (10 cm) it does not.
BOX = Box((0.05, 0.03, 0.04), center=np.array([0.5, 0.0, 0.04]))


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


SEEDS = range(5)


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    """The default planner, on the planner config without the voxel thinning of the shared
    cleaning: these tests check the network's frames on the cloud as given."""
    from hsqbench.planner.learned.config import resolve_contact_graspnet_config
    from hsqbench.planner.learned.contact_graspnet import ContactGraspNetPlanner

    unthinned = tmp_path_factory.mktemp("cgn") / "planner_unthinned.yaml"
    unthinned.write_text("extends: planner\nadditions:\n  thinning: false\n")
    config = dataclasses.replace(resolve_contact_graspnet_config(None), planner=str(unthinned))
    return ContactGraspNetPlanner(config)


@pytest.fixture(scope="module")
def plans(planner):
    """The default planner's result on the box for each of ``SEEDS``."""
    return [planner.plan(box_cloud(), context(seed)) for seed in SEEDS]


@pytest.fixture(scope="module")
def result(plans):
    return plans[0]


def closes_on_opposite_faces(grasp) -> bool:
    """Both contacts on the two faces normal to the box axis nearest the closing axis (within
    1 cm of their planes, on either side of the centre), closing within 30 deg of that axis."""
    local = grasp.contacts() - BOX.center
    axis = int(np.argmax(np.abs(grasp.closing_axis)))
    half = BOX.half_extents[axis]
    return bool(
        abs(grasp.closing_axis[axis]) > np.cos(np.deg2rad(30.0))
        and np.sign(local[0, axis]) != np.sign(local[1, axis])
        and np.all(np.abs(np.abs(local[:, axis]) - half) < 0.01)
    )


def test_every_grasp_has_a_finger_on_the_cloud_and_scores_in_order(planner):
    """The whole frame chain (world -> network frame -> poses -> Grasp): one finger of every grasp
    sits on the contact point the network chose, a point of the cloud it was given: the cleaned
    cloud (the planners' shared cleaning thins a dense cloud to voxel centroids), with the
    adapter's own input voxels off."""
    from hsqbench.planner.baselines.planner import clean_input
    from hsqbench.planner.hsq.config import resolve_config
    from hsqbench.planner.learned.contact_graspnet import ContactGraspNetPlanner

    exact = ContactGraspNetPlanner(dataclasses.replace(planner.config, input_voxel_m=0.0))
    result = exact.plan(box_cloud(), context(2))
    assert result.planner == "contact-graspnet"
    assert len(result.grasps) >= 3, result.reason
    cleaning = resolve_config(planner.config.planner).cleaning
    cloud = clean_input(box_cloud(), cleaning).points
    scores = [g.score for g in result.grasps]
    assert scores == sorted(scores, reverse=True)
    assert all(0.5 <= s <= 1.0 for s in scores)
    for grasp in result.grasps:
        gap = np.linalg.norm(cloud[:, None, :] - grasp.contacts()[None], axis=2).min(axis=0)
        assert gap.min() < 1e-6


def test_top_grasps_close_on_opposite_faces_of_the_box(plans):
    # Measured 10 of the top ten for each of seeds 0-4 with the pure-torch neighbourhoods
    # (cluster_ops: each PointNet++ ball a uniform draw, as in training on a GPU); torch-cluster's
    # CPU balls (a k-d tree's subset) gave 0, 0, 4, 4 and 3, and the 64 nearest points 2, 6, 4, 6
    # and 0. A wrong frame, a misplaced P_G or biased neighbourhoods give far fewer.
    n_opposite = sum(closes_on_opposite_faces(g) for plan in plans for g in plan.grasps[:10])
    assert n_opposite >= 40, n_opposite


def test_grasps_approach_from_outside_the_box(plans):
    for grasp in [g for plan in plans for g in plan.grasps]:
        palm = grasp.position - 0.1034 * grasp.approach_axis
        local = np.abs(palm - BOX.center)
        assert np.any(local > np.asarray(BOX.half_extents) + 0.01)  # the palm is outside
        assert palm[2] > 0.0  # above the table


def test_same_seed_same_grasps_and_timings_reported(planner, plans):
    again = planner.plan(box_cloud(), context(SEEDS[-1]))
    first = plans[-1]
    assert len(again.grasps) == len(first.grasps) > 0
    for i in range(len(first.grasps)):
        np.testing.assert_array_equal(again.grasps[i].position, first.grasps[i].position)
        assert again.grasps[i].score == first.grasps[i].score
    assert len({len(p.grasps) for p in plans}) > 1  # the seed matters
    assert first.timings["network"] > 0 and first.timings["total"] >= first.timings["network"]


def test_elimination_variant_keeps_only_grasps_that_pass_the_rules(planner, plans):
    from hsqbench.planner.learned.contact_graspnet import ContactGraspNetPlanner

    elim = ContactGraspNetPlanner(planner.config, eliminate=True, name="contact-graspnet-elim")
    survivors = []
    for seed, plain in zip(SEEDS, plans, strict=True):
        plan = elim.plan(box_cloud(), context(seed))
        assert plan.planner == "contact-graspnet-elim"
        assert plan.remaining["synthesised"] == len(plain.candidates)
        assert len(plan.grasps) == plan.candidates.counts_by_reason()["kept"]
        assert sum(plan.removed_by.values()) == plan.remaining["synthesised"] - len(plan.grasps)
        survivors += list(plan.grasps)
    # Measured 28, 26, 28, 29 and 22 survivors for seeds 0-4, every one across the 6 cm faces
    # (with torch-cluster's CPU neighbourhoods 0, 0, 2, 8 and 5).
    assert len(survivors) >= 60
    assert all(closes_on_opposite_faces(g) for g in survivors)


def test_per_image_views_run_each_cameras_own_points(planner):
    """views: per_image: each camera's part of the cloud read off its depth image, one network
    pass per camera (as the network was trained on one view); without images, one clear line."""
    from tests.volumetric_scene import render

    lower, upper = BOX.center - BOX.half_extents, BOX.center + BOX.half_extents
    views = tuple(render(c, [(lower, upper)]) for c in CAMERAS)
    per_image = type(planner)(dataclasses.replace(planner.config, views="per_image"))
    ctx = PlanningContext(support_plane=TABLE, seed=0, camera_positions=CAMERAS, depth_views=views)
    result = per_image.plan(box_cloud(), ctx)
    assert result.grasps
    assert sum(closes_on_opposite_faces(g) for g in result.grasps[:10]) >= 5
    with pytest.raises(ValueError, match="depth_views"):
        per_image.plan(box_cloud(), context())
