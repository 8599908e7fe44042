"""The privileged oracle: antipodal grasps on true hulls, the table, collisions, no cloud."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.oracle import OraclePlanner, feasible_grasps, load_oracle_config
from hsqbench.planner.truth import ObjectTruth, SceneTruth
from hsqbench.sim.scene_truth import panda_hand

TABLE = (0.0, 0.0, 1.0, 0.0)


def box(name: str, size, centre=(0.5, 0.0), yaw: float = 0.0) -> ObjectTruth:
    """A box on the table (z = 0) as one hull."""
    half = np.asarray(size, float) / 2
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return ObjectTruth(name, (corners @ rot.T + [centre[0], centre[1], half[2]],))


def resting_boxes(size) -> list[ObjectTruth]:
    """The box on each of its faces (the six resting poses of a box, by symmetry three)."""
    size = np.asarray(size, float)
    return [box(f"b{k}", np.roll(size, k)) for k in range(3)]


@pytest.fixture(scope="module")
def oracle() -> OraclePlanner:
    return OraclePlanner()


def test_a_5cm_cube_is_graspable(oracle):
    counts = feasible_grasps(
        SceneTruth((box("cube", [0.05] * 3),), TABLE), oracle.gripper, oracle.config, seed=0
    )
    assert counts["cube"] > 0


def test_a_box_wider_than_the_opening_in_every_resting_pose_is_not(oracle):
    # 9 x 10 x 12 cm: every pair of opposite faces is farther apart than the 8 cm opening.
    for obj in resting_boxes([0.09, 0.10, 0.12]):
        counts = feasible_grasps(SceneTruth((obj,), TABLE), oracle.gripper, oracle.config, 0)
        assert counts[obj.name] == 0


def test_grasps_pinch_opposite_faces_and_stay_off_the_table(oracle):
    truth = SceneTruth((box("slab", [0.04, 0.20, 0.06]),), TABLE)
    plan = oracle.plan(None, PlanningContext(support_plane=TABLE, truth=truth))
    assert len(plan.grasps) > 0
    for g in list(plan.grasps)[:20]:
        closing = g.rotation[:, 0]
        assert abs(closing[0]) > np.cos(np.arctan(panda_hand().pad_friction)) - 1e-9
        # Both contacts on the two 4 cm-apart faces: the line spans exactly 4 cm along x.
        assert g.width * abs(closing[0]) == pytest.approx(0.04, abs=1e-9)
        # Contacts at most 6 cm up: a hand coming from below would have its palm in the table.
        assert g.rotation[2, 2] < 0.5


def test_a_neighbour_in_the_fingers_path_removes_grasps(oracle):
    cube = box("cube", [0.05] * 3)
    alone = feasible_grasps(SceneTruth((cube,), TABLE), oracle.gripper, oracle.config, 0)
    # Two low walls 1 cm from the cube's sides along x leave no room for a finger there; the
    # grasps closing along y stay.
    walls = (box("w1", [0.01, 0.2, 0.03], (0.54, 0.0)), box("w2", [0.01, 0.2, 0.03], (0.46, 0.0)))
    crowded = feasible_grasps(SceneTruth((cube, *walls), TABLE), oracle.gripper, oracle.config, 0)
    assert 0 < crowded["cube"] < alone["cube"]


def test_the_oracle_never_reads_the_cloud(oracle):
    class Untouchable:
        def __getattr__(self, name):
            raise AssertionError("the oracle read the cloud")

        def __array__(self, *args, **kwargs):
            raise AssertionError("the oracle read the cloud")

    truth = SceneTruth((box("cube", [0.05] * 3),), TABLE)
    plan = oracle.plan(Untouchable(), PlanningContext(support_plane=TABLE, truth=truth))
    assert len(plan.grasps) > 0


def test_without_truth_the_oracle_says_what_it_needs(oracle):
    with pytest.raises(ValueError, match="truth"):
        oracle.plan(np.zeros((10, 3)), PlanningContext(support_plane=TABLE))


def test_same_seed_same_grasps_and_the_config_is_checked():
    truth = SceneTruth((box("cube", [0.05] * 3),), TABLE)
    p = OraclePlanner()
    a = p.plan(None, PlanningContext(support_plane=TABLE, truth=truth, seed=3))
    b = p.plan(None, PlanningContext(support_plane=TABLE, truth=truth, seed=3))
    np.testing.assert_array_equal(a.grasps[0].position, b.grasps[0].position)
    assert load_oracle_config().contact_shifts >= 1


def test_the_planner_finds_grasps_exactly_where_the_check_says_graspable(oracle):
    scenes = [
        box("cube", [0.05] * 3),
        box("slab", [0.02, 0.3, 0.1]),
        box("wide", [0.09, 0.1, 0.12]),
    ]
    for seed, obj in enumerate(scenes):
        truth = SceneTruth((obj,), TABLE, seed=seed)
        counts = feasible_grasps(truth, oracle.gripper, oracle.config, truth.seed)
        plan = oracle.plan(None, PlanningContext(support_plane=TABLE, truth=truth, seed=99))
        assert (counts[obj.name] > 0) == (len(plan.grasps) > 0)
        assert len(plan.grasps) >= counts[obj.name]


def prism(name: str, side: float, length: float, centre=(0.5, 0.0)) -> ObjectTruth:
    """A prism of equilateral cross-section lying on a face, its axis along y."""
    tri = np.array([[-side / 2, 0.0], [side / 2, 0.0], [0.0, side * np.sqrt(3) / 2]])
    v = np.array([[x, y, z] for y in (-length / 2, length / 2) for x, z in tri])
    return ObjectTruth(name, (v + np.array([centre[0], centre[1], 0.0]),))


def test_a_thin_flat_box_on_the_table_is_graspable_near_the_fingertips(oracle):
    # 1 cm tall: the fingertips reach 8.9 mm past the TCP, so contacts at the TCP would put
    # them into the table; the contacts sit lower on the pads with the hand held up.
    flat = box("flat", [0.02, 0.20, 0.01])
    truth = SceneTruth((flat,), TABLE, seed=0)
    assert feasible_grasps(truth, oracle.gripper, oracle.config, 0)["flat"] > 0
    hand = panda_hand()
    for g in list(oracle.plan(None, PlanningContext(support_plane=TABLE, truth=truth)).grasps):
        # No vertex of the true fingers comes within the clearance of the table.
        for finger, side in ((hand.left_finger, 1), (hand.right_finger, -1)):
            local = finger + np.array([side * 0.5 * g.approach_width, 0.0, 0.0])
            world = g.position + local @ g.rotation.T
            assert world[:, 2].min() >= oracle.config.table_clearance_m - 1e-9


def test_the_contact_friction_is_the_simulations_not_a_narrower_cone(oracle):
    # Every pair of faces of an equilateral prism is 60 deg off antipodal: a closing line needs
    # mu >= tan 30 deg = 0.58; the ends are 12 cm apart, wider than the hand opens.
    truth = SceneTruth((prism("prism", 0.05, 0.12),), TABLE)
    assert panda_hand().contact_friction(truth.objects[0]) >= 1.0  # pads 1.0 (robot.yaml)
    assert feasible_grasps(truth, oracle.gripper, oracle.config, 0)["prism"] > 0
    narrow = dataclasses.replace(oracle.config, friction_coefficient=0.5)
    assert feasible_grasps(truth, oracle.gripper, narrow, 0)["prism"] == 0


def test_a_ball_no_chord_of_which_the_pads_can_hold_is_not_graspable(oracle):
    # A 12 cm ball: a chord the 8 cm hand spans meets the surface at >= 50 deg off its normal,
    # beyond the pads' friction cone (45 deg at mu 1).
    ball = ObjectTruth("ball", (_sphere(0.06, (0.5, 0.0, 0.06)),))
    truth = SceneTruth((ball,), TABLE)
    assert feasible_grasps(truth, oracle.gripper, oracle.config, 0)["ball"] == 0


def _sphere(radius: float, centre) -> np.ndarray:
    """Vertices of a fine polyhedral sphere."""
    u, v = np.meshgrid(np.linspace(0, np.pi, 24), np.linspace(0, 2 * np.pi, 48))
    pts = np.stack([np.sin(u) * np.cos(v), np.sin(u) * np.sin(v), np.cos(u)], -1).reshape(-1, 3)
    return np.unique(np.round(pts, 9), axis=0) * radius + centre
