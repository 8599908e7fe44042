"""VGN/GIGA's clutter removal (hsqbench.sim.clutter): the free hand's grasp sequence on a box,
their camera, their depth noise, and their round rule on sequences counted by hand."""

from __future__ import annotations

import dataclasses
import itertools
from pathlib import Path

import numpy as np
import pytest

from hsqbench.sim.clutter.config import ClutterCameraConfig, ClutterConfig, HandExecutionConfig
from hsqbench.sim.clutter.execution import execute_hand_grasp, retreat_position
from hsqbench.sim.clutter.world import camera_eyes, compile_world
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.physics import load_physics_config
from hsqbench.sim.robot import load_robot_config
from hsqbench.sim.sensor_noise import DexNoiseConfig, apply_dex_noise
from tests.test_robot import make_box

#: Closing along world x, approach straight down (rotation columns: closing, third, approach).
DOWN = np.column_stack([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
CENTRE = np.array([0.15, 0.15])


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    """One world with a 4 x 4 x 8 cm, 100 g box (compiled once: the hand's meshes take s)."""
    folder: Path = tmp_path_factory.mktemp("box")
    box = make_box(folder, (0.04, 0.04, 0.08), 0.1)
    world = compile_world([box], [1.0], ClutterConfig(), load_robot_config(), load_physics_config())
    return world, box


def _fresh(compiled, hand: HandExecutionConfig | None = None):
    """The world with the box upright at rest in the middle and the hand parked."""
    world, box = compiled
    world.config = dataclasses.replace(ClutterConfig(), hand=hand or HandExecutionConfig())
    world.hand.teleport(world.data, np.array(world.config.hand.park_m), np.eye(3))
    top = world.table_z + 0.002
    world.bring_in(box.name, np.array([*CENTRE, top]), np.array([1.0, 0.0, 0.0, 0.0]))
    world.wait_to_rest(1.0)
    return world, box.name


def test_the_hand_grasps_and_lifts_a_box_from_above(compiled) -> None:
    world, box = _fresh(compiled)
    grasp = np.array([*CENTRE, world.table_z + 0.05])
    res = execute_hand_grasp(world, grasp, DOWN)
    assert res.outcome == Outcome.SUCCESS and res.target == box
    assert res.width_m == pytest.approx(0.04, abs=0.004)  # measured on the box, then released
    assert world.in_play == []  # the held object is taken out of the world
    # 5 cm approach and 10 cm lift at 0.1 m/s, plus the closing.
    assert 1.5 < res.sim_time_s < 1.5 + world.config.hand.close_time_s + 0.1
    assert world.hand.tcp_position(world.data)[0] > 4.0  # parked again


def test_a_contact_at_the_pregrasp_fails_without_moving(compiled) -> None:
    world, box = _fresh(compiled)
    # 3 cm off the box's centre along the closing axis, 1 cm above the table: 5 cm back, one
    # open finger (4 cm from the TCP) is still inside the 8 cm tall box.
    res = execute_hand_grasp(world, np.array([0.18, 0.15, world.table_z + 0.01]), DOWN)
    assert res.outcome == Outcome.COLLISION_ON_APPROACH
    assert "pre-grasp" in res.detail and res.sim_time_s == 0.0
    assert world.in_play == [box]


def test_closing_on_nothing_is_an_empty_grasp(compiled) -> None:
    world, box = _fresh(compiled)
    res = execute_hand_grasp(world, np.array([0.05, 0.05, world.table_z + 0.05]), DOWN)
    assert res.outcome == Outcome.EMPTY_GRASP and "closed to" in res.detail
    assert world.in_play == [box]


def test_a_contact_on_the_approach_stops_it_and_their_clutter_runs_close_anyway(compiled):
    # The palm's face lies 3.7 cm behind the TCP (gripper.yaml jaw_length_m): with the goal
    # 6 cm into the box's top it meets the top 2.3 cm short, the pads around the box.
    goal = np.array([*CENTRE, 0.0])
    allowed, _ = _fresh(compiled)
    goal[2] = allowed.table_z + 0.08 - 0.06
    res = execute_hand_grasp(allowed, goal, DOWN)
    assert "approach stopped by a contact 2." in res.detail
    assert res.outcome == Outcome.SUCCESS  # closed where it stopped: still around the box
    strict, _ = _fresh(compiled, HandExecutionConfig(allow_contact=False))
    res = execute_hand_grasp(strict, goal, DOWN)
    assert res.outcome == Outcome.COLLISION_ON_APPROACH and "approach" in res.detail


@pytest.mark.parametrize(
    ("approach", "expected"),
    [
        ([0.0, 0.0, -1.0], [0.0, 0.0, 0.1]),  # from above: back along the approach = up
        ([1.0, 0.0, 0.0], [0.0, 0.0, 0.1]),  # side grasp (90 deg): straight up, not back
        ([np.sqrt(0.5), 0.0, -np.sqrt(0.5)], [-0.1 * np.sqrt(0.5), 0.0, 0.1 * np.sqrt(0.5)]),
        ([np.sin(np.radians(61)), 0.0, -np.cos(np.radians(61))], [0.0, 0.0, 0.1]),  # > 60 deg
    ],
)
def test_the_lift_is_back_along_the_approach_unless_a_side_grasp(approach, expected) -> None:
    a = np.asarray(approach)
    closing = np.array([0.0, 1.0, 0.0])
    rotation = np.column_stack([closing, np.cross(a, closing), a])
    got = retreat_position(np.zeros(3), rotation, 0.1, 60.0)
    assert got == pytest.approx(np.asarray(expected), abs=1e-12)


def test_their_side_view_sits_on_the_cubes_minus_y_side() -> None:
    eyes, target = camera_eyes(ClutterCameraConfig(), 0.3)
    # camera_on_sphere(origin (0.15, 0.15, 0.1), r 0.6, theta pi/3, phi -pi/2)
    assert target == pytest.approx([0.15, 0.15, 0.1])
    assert eyes[0] == pytest.approx([0.15, 0.15 - 0.6 * np.sin(np.pi / 3), 0.1 + 0.3])
    assert len(eyes) == 1
    ring, _ = camera_eyes(ClutterCameraConfig(views="ring"), 0.3)
    assert len(ring) == 6 and ring[:, 2] == pytest.approx(0.6 * np.cos(np.pi / 6))
    assert ClutterCameraConfig().fovy_deg == pytest.approx(2 * np.degrees(np.arctan(240 / 540)))


def test_dex_noise_scales_the_image_and_warps_it_smoothly() -> None:
    depth = np.full((48, 64), 0.6, dtype=np.float32)
    depth[:4] = 0.0  # invalid pixels stay invalid
    scale_only = apply_dex_noise(depth, DexNoiseConfig(gp_rate=0.0), np.random.default_rng(1))
    factor = scale_only[10, 10] / 0.6
    assert np.allclose(scale_only[4:], 0.6 * factor) and (scale_only[:4] == 0).all()
    assert factor != 1.0 and abs(factor - 1.0) < 0.15  # gamma(1000, 0.001): sd 3 %
    warped = apply_dex_noise(depth, DexNoiseConfig(gp_rate=1.0), np.random.default_rng(1))
    off = warped[4:] - 0.6 * factor
    assert 0.002 < off.std() < 0.008  # the 5 mm warp
    # Smooth: neighbours differ by a fraction of the warp (drawn on a 4x coarser grid).
    assert np.abs(np.diff(off, axis=1)).mean() < 0.5 * off.std()


def _their_loop(labels: list[bool]) -> int:
    """GIGA's clutter_removal.run counter, transcribed: attempts made before it stops."""
    consecutive, last, n = 1, None, 0
    for ok in labels:
        if consecutive >= 2:
            break
        n += 1
        if last is False and ok is False:
            consecutive += 1
        else:
            consecutive = 1
        last = ok
    return n


@pytest.mark.parametrize("labels", list(itertools.product([True, False], repeat=6)))
def test_the_round_stops_where_their_counter_stops(labels) -> None:
    """Objects never run out here (8 left): only the two-failure rule can stop the round."""
    rule = ClutterConfig().rule
    outcomes: list[str] = []
    for ok in labels:
        if rule.stop_reason(outcomes, objects_left=True) is not None:
            break
        outcomes.append("success" if ok else "empty_grasp")
    assert len(outcomes) == _their_loop(list(labels))


def test_the_round_stops_at_the_first_step_without_a_grasp_or_when_clear() -> None:
    rule = ClutterConfig().rule
    assert rule.stop_reason(["success", "no_grasp_found"], True) == "no grasp found"
    assert rule.stop_reason(["success", "dropped"], True) is None
    assert rule.stop_reason(["success"] * 5, False) == "the table is clear"


def test_until_names_a_phase() -> None:
    from hsqbench.sim.trial.execution import execute_grasp

    with pytest.raises(ValueError, match="until must be one of the phases"):
        execute_grasp(None, None, "", until="carry_on")  # type: ignore[arg-type]


def test_the_arm_meets_the_hands_scene_shifted_onto_its_table(compiled) -> None:
    """The bridge's first step: the same objects at the same poses in the arm's world, their
    camera moved with them."""
    from hsqbench.sim.clutter.arm import arm_env
    from hsqbench.sim.trial import load_trial_config

    world, box = _fresh(compiled)
    before = world.com(box)
    env, origin = arm_env(world, "packed", 0, load_trial_config("trial_clutter_arm"))
    assert origin[:2] == pytest.approx([0.35, -0.15])
    assert origin[2] == pytest.approx(env.info.table_top_z - 0.05)
    after = env.data.xipos[env.info.object_body_ids[box]] - origin
    assert after == pytest.approx(before, abs=0.003)  # settled again with the arm at home
    cam = env.model.camera("clutter_cam0").id
    eye, _ = camera_eyes(world.config.camera, 0.3)
    assert env.data.cam_xpos[cam] - origin == pytest.approx(eye[0], abs=1e-9)
    assert [c.name for c in env.info.depth_cameras] == ["clutter_cam0"]
    env.close()


def test_the_second_step_sees_with_the_harness_cameras(compiled) -> None:
    from hsqbench.sim.clutter.arm import arm_env
    from hsqbench.sim.trial import load_trial_config

    world, _ = _fresh(compiled)
    config = load_trial_config("trial_clutter_arm_cameras")
    world.config = config.clutter
    env, _ = arm_env(world, "packed", 0, config)
    assert [c.name for c in env.info.depth_cameras] == ["cam_left", "cam_right"]
    assert env.config.perception == config.perception  # tof+calibration, not their dex noise
    assert load_trial_config("trial_clutter_arm_bin").clutter.arm_until == "release"
    env.close()


def test_their_packed_generation_places_upright_boxes_apart_on_the_table(tmp_path) -> None:
    from hsqbench.sim.clutter.scenes import generate_packed

    boxes = [make_box(tmp_path, (0.04, 0.05, 0.06), 0.1, name=f"box{i}") for i in range(3)]
    world = compile_world(
        boxes, [0.8] * 3, ClutterConfig(), load_robot_config(), load_physics_config()
    )
    unplaced = generate_packed(world, np.random.default_rng(3))
    assert unplaced == [] and sorted(world.in_play) == ["box0", "box1", "box2"]
    for name in world.in_play:
        pose = world.pose(name)
        assert 0.06 <= pose[0] <= 0.24 and 0.06 <= pose[1] <= 0.24  # 0.08-0.22, then settled
        assert pose[2] == pytest.approx(world.table_z, abs=0.003)  # base on the table
        assert abs(pose[3]) ** 2 + pose[6] ** 2 == pytest.approx(1.0, abs=1e-3)  # yaw only
        assert world.touching_objects(name) == []  # placed apart
    half = world.model.geom_size[world.geom_ids["box0"][0]].max()
    assert half == pytest.approx(0.8 * 0.03, abs=1e-4)  # the 6 cm side scaled 0.8


def test_round_tally_clears_only_successes_and_marks_the_lost():
    from hsqbench.sim.clutter.step import RoundTally
    from hsqbench.sim.outcome import Attempt, Outcome

    tally = RoundTally()
    won = Attempt(Outcome.SUCCESS, target="apple")
    missed = Attempt(Outcome.DROPPED, target="banana", detail="dropped")
    tally.record(won)
    tally.record(missed)
    tally.lose(missed, ["banana"])
    assert tally.outcomes == ["success", "dropped"]
    assert tally.cleared == ["apple"] and tally.lost == ["banana"]
    assert missed.detail == "dropped; banana left the workspace (taken out, not cleared)"
    r = tally.result(["apple", "banana"], ["dice"], 7, "oracle")
    assert (r.objects_cleared, r.objects_lost, r.objects_unplaced) == (
        ["apple"],
        ["banana"],
        ["dice"],
    )
    assert r.planner == "oracle" and r.clearance_rate == 0.5


def test_a_hand_round_on_one_box_clears_it_and_stops_on_a_clear_table(compiled) -> None:
    from hsqbench.sim.clutter.round import run_hand_round
    from hsqbench.sim.trial import load_trial_config

    world, box = _fresh(compiled)
    result = run_hand_round(world, "packed", 0, "oracle", load_trial_config("trial_clutter"))
    assert [a.outcome for a in result.attempts] == [Outcome.SUCCESS]
    assert result.objects == [box] and result.objects_cleared == [box]
    assert result.objects_lost == [] and result.objects_unplaced == []
    assert result.planner == "oracle" and result.seed == 0


def test_an_arm_round_on_one_box_clears_it_and_stops_on_a_clear_table(compiled) -> None:
    from hsqbench.sim.clutter.arm import run_arm_round
    from hsqbench.sim.trial import load_trial_config

    world, box = _fresh(compiled)
    result = run_arm_round(world, "packed", 0, "oracle", load_trial_config("trial_clutter_arm"))
    assert [a.outcome for a in result.attempts] == [Outcome.SUCCESS]
    assert result.attempts[0].detail.startswith("held after the lift")
    assert result.objects == [box] and result.objects_cleared == [box]
    assert result.objects_lost == [] and result.objects_unplaced == []
