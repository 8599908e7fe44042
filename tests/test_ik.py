"""IK of the Panda's TCP (hsqbench.sim.ik) in the benchmark scene."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from hsqbench.sim.ik import FLIP_ABOUT_APPROACH, ArmIK, IKConfig, Pose, line_poses
from hsqbench.sim.robot import Panda
from hsqbench.sim.scene import build_scene

DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])


def rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def side_rotation(azimuth: float) -> np.ndarray:
    """Horizontal approach pointing away from the base, closing axis horizontal."""
    approach = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
    closing = np.array([-np.sin(azimuth), np.cos(azimuth), 0.0])
    return np.column_stack([closing, np.cross(approach, closing), approach])


@pytest.fixture(scope="module")
def scene():
    model, data, info = build_scene("isolated", "proc_box", seed=0)
    panda = Panda(model, info.robot_prefix)
    ik = ArmIK(model, panda, IKConfig(), [info.table_geom_id, *info.bin_geom_ids])
    ik.sync(data, panda.max_width())
    return model, data, info, panda, ik


def fk(model: mujoco.MjModel, data: mujoco.MjData, panda: Panda, q: np.ndarray) -> Pose:
    """Independent forward kinematics on a fresh MjData."""
    d = mujoco.MjData(model)
    d.qpos[:] = data.qpos
    d.qpos[panda.arm_qpos_adr] = q
    mujoco.mj_kinematics(model, d)
    return Pose(*panda.tcp_pose(d))


def workspace_targets(rng: np.random.Generator) -> list[Pose]:
    """Top-down grasps over the whole workspace at two heights, and side grasps (radial
    approach) at mid height where the hand is not over the robot's base: nearer than ~0.4 m a
    horizontal hand needs the elbow folded to its limit."""
    targets = []
    for x in np.linspace(0.34, 0.66, 3):
        for y in np.linspace(-0.23, 0.23, 3):
            for z in (0.04, 0.2):
                targets.append(Pose([x, y, z], rot_z(rng.uniform(-np.pi / 2, np.pi / 2)) @ DOWN))
            if x > 0.4:
                targets.append(Pose([x, y, 0.12], side_rotation(np.arctan2(y, x))))
    return targets


def test_reaches_poses_across_the_workspace(scene):
    """Every target, or its twin turned by pi about the approach axis (the same parallel-jaw
    grasp, as the trial runner tries it), is reached within tolerance and limits."""
    model, data, _, panda, ik = scene
    cfg = ik.config
    rng = np.random.default_rng(0)
    lo, hi = ik.lower, ik.upper
    for twins in workspace_targets(rng):
        for target in (twins, twins.flipped()):
            sol = ik.solve(target, panda.home_arm_q, rng)
            if sol.ok:
                break
        assert sol.ok, f"{target.position}: {sol.reason}"
        assert np.all(sol.q >= lo - 1e-9) and np.all(sol.q <= hi + 1e-9)
        reached = fk(model, data, panda, sol.q)
        assert np.linalg.norm(reached.position - target.position) <= cfg.position_tolerance_m
        c = 0.5 * (np.trace(reached.rotation.T @ target.rotation) - 1.0)
        assert np.degrees(np.arccos(np.clip(c, -1, 1))) <= cfg.orientation_tolerance_deg
        assert sol.clearance_m >= cfg.clearance_m


def test_impossible_poses_are_unreachable(scene):
    _, _, _, panda, ik = scene
    rng = np.random.default_rng(1)
    far = ik.solve(Pose([1.3, 0.0, 0.3], DOWN), panda.home_arm_q, rng)
    assert not far.ok
    assert "pose error" in far.reason
    # Reachable by the arm, but the fingers would be 2 cm inside the table.
    in_table = ik.solve(Pose([0.5, 0.0, -0.02], DOWN), panda.home_arm_q, rng)
    assert not in_table.ok
    assert "table or bin" in in_table.reason


def test_ik_leaves_the_simulation_state_alone(scene):
    _, data, _, panda, ik = scene
    before = (data.qpos.copy(), data.qvel.copy(), data.ctrl.copy(), data.time)
    ik.solve(Pose([0.5, 0.1, 0.1], DOWN), panda.home_arm_q, np.random.default_rng(2))
    assert np.array_equal(data.qpos, before[0])
    assert np.array_equal(data.qvel, before[1])
    assert np.array_equal(data.ctrl, before[2])
    assert data.time == before[3]


def test_closest_to_prefers_a_short_move(scene):
    _, _, _, panda, ik = scene
    target = Pose([0.5, -0.15, 0.15], rot_z(0.4) @ DOWN)
    home = panda.home_arm_q
    first = ik.solve(target, home + 0.9, np.random.default_rng(3))
    closest = ik.solve(target, home + 0.9, np.random.default_rng(3), closest_to=home)
    assert first.ok and closest.ok

    def cost(q):
        dq = np.abs(q - home)
        return dq.max() + 0.1 * np.linalg.norm(dq)

    assert closest.restarts == ik.config.restarts  # every restart ran
    assert cost(closest.q) <= cost(first.q) + 1e-9


def test_path_follows_a_line_without_branch_jumps(scene):
    model, data, _, panda, ik = scene
    start = Pose([0.45, 0.1, 0.25], rot_z(0.3) @ DOWN)
    poses = line_poses(start, [0.45, 0.1, 0.05], 5)
    assert len(poses) == 6
    first = ik.solve(start, panda.home_arm_q, np.random.default_rng(4))
    path = ik.solve_path(poses, first.q)
    assert path.ok, path.reason
    assert path.q.shape == (6, 7)
    assert np.abs(np.diff(path.q, axis=0)).max() <= ik.config.max_waypoint_jump_rad
    for q, pose in zip(path.q, poses, strict=True):
        assert np.linalg.norm(fk(model, data, panda, q).position - pose.position) < 0.003


def test_flipped_pose_is_the_same_parallel_jaw_grasp():
    pose = Pose([0.5, 0.0, 0.1], rot_z(0.7) @ DOWN)
    twin = pose.flipped()
    assert np.allclose(twin.rotation[:, 2], pose.rotation[:, 2])
    assert np.allclose(twin.rotation[:, 0], -pose.rotation[:, 0])
    assert np.allclose(twin.flipped().rotation, pose.rotation)
    assert np.allclose(FLIP_ABOUT_APPROACH @ FLIP_ABOUT_APPROACH, np.eye(3))


def test_bad_poses_and_config_are_refused():
    with pytest.raises(ValueError, match="proper rotation"):
        Pose([0.0, 0.0, 0.0], np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="finite"):
        Pose([np.nan, 0.0, 0.0], np.eye(3))
    with pytest.raises(ValueError, match="position_tolerance_m"):
        IKConfig(position_tolerance_m=0.0)
    with pytest.raises(ValueError, match="segment"):
        line_poses(Pose([0, 0, 0], np.eye(3)), [0, 0, 1], 0)


def _points_hit_everywhere(ik: ArmIK, qs, points, margin_m: float, min_points: int):
    """``ArmIK.points_hit`` without its sphere pre-test: every geom's box at every sample."""
    m, d, g = ik.model, ik.data, ik.robot_geoms
    centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:] + margin_m
    for k, q in enumerate(qs):
        ik.configuration.update(ik._full_q(q))
        rot = d.geom_xmat[g].reshape(-1, 3, 3)
        local = np.einsum("gji,gmj->gmi", rot, points[None] - d.geom_xpos[g][:, None])
        counts = np.all(np.abs(local - centre[:, None]) <= half[:, None], axis=2).sum(axis=1)
        if counts.max() >= min_points:
            i = int(np.argmax(counts))
            return k, int(g[i]), int(counts[i])
    return -1, -1, 0


def test_points_hit_finds_what_testing_every_box_finds(scene):
    """The first sample, geom and count at which the arm's boxes meet a cloud: the same as
    testing every geom's box at every sample, for clouds near the hand's path and far off."""
    _, _, _, panda, ik = scene
    rng = np.random.default_rng(3)
    start = panda.home_arm_q
    hits = 0
    for _ in range(40):
        qs = np.linspace(start, start + rng.normal(0.0, 0.5, 7), 12)
        centre = ik.forward(qs[rng.integers(12)]).position + rng.normal(0.0, 0.05, 3)
        points = centre + rng.normal(0.0, rng.uniform(0.005, 0.1), (int(rng.integers(20, 400)), 3))
        margin, need = float(rng.uniform(0.0, 0.02)), int(rng.integers(1, 6))
        found = ik.points_hit(qs, points, margin, need)
        assert found == _points_hit_everywhere(ik, qs, points, margin, need)
        hits += found[0] >= 0
    assert 5 < hits < 40  # both kinds of motion were checked
    far = np.full((10, 3), 5.0)
    assert ik.points_hit(qs, far, 0.01, 1) == (-1, -1, 0)
    assert ik.points_hit(qs, np.zeros((0, 3)), 0.01, 1) == (-1, -1, 0)
