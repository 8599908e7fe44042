"""The trial runner and the simulator's truth: graspability, the oracle, resting poses.

Fast: the surface stand-in sensor and procedural objects.
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from hsqbench.assets.library import get_object
from hsqbench.assets.resting import resting_poses
from hsqbench.planner.api import PlanResult
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.scene import build_scene, load_scene_config
from hsqbench.sim.trial import load_trial_config, run_isolated_trial


@pytest.fixture(scope="module")
def config():
    return replace(load_trial_config(), sensor="surface")


class Spy:
    """Records what the context held; plans nothing."""

    def __init__(self, privileged: bool) -> None:
        self.name = "spy"
        self.privileged = privileged
        self.truths = []

    def plan(self, points, context) -> PlanResult:
        self.truths.append(context.truth)
        return PlanResult(grasps=[], reason="spy", planner=self.name)


def test_only_privileged_planners_see_the_truth(config):
    plain, privileged = Spy(False), Spy(True)
    run_isolated_trial("proc_box", 2, plain, config)
    run_isolated_trial("proc_box", 2, privileged, config)
    assert plain.truths == [None]
    [truth] = privileged.truths
    assert truth.names == ("proc_box",)
    # The hulls are where the box is: on the table, inside the workspace.
    z = np.concatenate([h[:, 2] for o in truth.objects for h in o.hulls])
    assert z.min() == pytest.approx(0.0, abs=2e-3) and z.max() > 0.05


def test_the_oracle_grasps_the_box_and_marks_it_graspable(config):
    result = run_isolated_trial("proc_box", 1, "oracle", config)
    [attempt] = result.attempts
    assert attempt.outcome == Outcome.SUCCESS, attempt.detail
    assert attempt.graspable is True
    assert len(attempt.object_pose) == 7 and attempt.resting_pose == -1
    # Every planner is told the same graspability for the same pose (seed).
    other = run_isolated_trial("proc_box", 1, Spy(False), config).attempts[0]
    assert other.graspable is True and other.object_pose == attempt.object_pose


def test_the_check_can_be_turned_off(config):
    [attempt] = run_isolated_trial(
        "proc_box", 1, Spy(False), replace(config, graspability=None)
    ).attempts
    assert attempt.graspable is None


def test_resting_placement_draws_a_stable_pose_and_keeps_it():
    scene = load_scene_config("scene_resting")
    box = get_object("proc_box")
    poses = resting_poses(box, scene.placement.min_resting_probability)
    assert len(poses.probabilities) == 6  # a box rests on each of its faces
    seen = set()
    for seed in range(12):
        info = build_scene("isolated", ["proc_box"], seed, scene_config=scene)[2]
        k = info.resting_poses["proc_box"]
        seen.add(k)
        quat = info.initial_poses["proc_box"][3:]
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, quat)
        # The box's up axis after settling is the drawn pose's up axis (no tipping over).
        up_drawn = poses.rotations[k].T @ [0, 0, 1]
        up_now = rot.reshape(3, 3).T @ [0, 0, 1]
        assert abs(up_drawn @ up_now) > 0.99
        assert info.max_speed_after_settle < 0.05
    assert len(seen) >= 3  # poses are drawn, not always the likeliest


def test_upright_placement_is_unchanged_by_the_resting_option():
    a = build_scene("isolated", ["proc_box"], 4)[2]
    b = build_scene("isolated", ["proc_box"], 4, scene_config=load_scene_config("scene"))[2]
    np.testing.assert_array_equal(a.initial_poses["proc_box"], b.initial_poses["proc_box"])
    assert a.resting_poses == {"proc_box": -1}
    np.testing.assert_allclose(
        a.initial_poses["proc_box"][3:5], [a.initial_poses["proc_box"][3], 0], atol=1e-3
    )
