"""Contact-GraspNet adapter, pure numpy (always runs): frames, grasp conversion, table patch,
views, config and the install hint when the extra is missing."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.learned import frames
from hsqbench.planner.learned.config import ContactGraspNetConfig, load_contact_graspnet_config
from tests.shapes import Box, random_rotation

DEPTH = 0.1034


def network_pose(contact, width, closing, approach, depth=DEPTH):
    """A gripper-base pose exactly as cgn-pytorch's build_6d_grasps writes it."""
    pose = np.eye(4)
    pose[:3, 0] = closing
    pose[:3, 2] = approach
    pose[:3, 1] = np.cross(approach, closing)
    pose[:3, 3] = contact - depth * approach + 0.5 * width * closing
    return pose


def random_grasp_axes(rng):
    rot = random_rotation(rng)
    return rot[:, 0], rot[:, 2]


def test_network_pose_becomes_grasp_with_contacts_at_the_predicted_points():
    rng = np.random.default_rng(0)
    for _ in range(20):
        closing, approach = random_grasp_axes(rng)
        contact = rng.uniform(-0.5, 0.5, 3)
        width = rng.uniform(0.0, 0.08)
        pos, rot = frames.network_to_grasp_frames(
            network_pose(contact, width, closing, approach)[None], DEPTH
        )
        grasp = Grasp(position=pos[0], rotation=rot[0], width=width, score=0.5)
        np.testing.assert_allclose(grasp.closing_axis, closing, atol=1e-12)
        np.testing.assert_allclose(grasp.approach_axis, approach, atol=1e-12)
        # One finger at the network's contact point, the other one width along the closing axis.
        np.testing.assert_allclose(grasp.contacts()[0], contact, atol=1e-12)
        np.testing.assert_allclose(grasp.contacts()[1], contact + width * closing, atol=1e-12)
        # The palm (network base) lies depth behind P_G along the approach.
        base = network_pose(contact, width, closing, approach)[:3, 3]
        np.testing.assert_allclose(grasp.position - DEPTH * approach, base, atol=1e-12)


def test_grasp_frames_round_trip_and_reorthonormalise_float32_poses():
    rng = np.random.default_rng(1)
    rots = np.stack([random_rotation(rng) for _ in range(50)])
    pos = rng.uniform(-1, 1, (50, 3))
    poses = frames.grasp_frames_to_network(pos, rots, DEPTH)
    back_pos, back_rot = frames.network_to_grasp_frames(poses.astype(np.float32), DEPTH)
    np.testing.assert_allclose(back_pos, pos, atol=1e-6)
    np.testing.assert_allclose(back_rot, rots, atol=1e-6)
    eye = np.einsum("gji,gjk->gik", back_rot, back_rot)
    np.testing.assert_allclose(eye, np.broadcast_to(np.eye(3), eye.shape), atol=1e-12)
    assert np.all(np.linalg.det(back_rot) > 0.999)


def test_look_at_frame_is_an_optical_frame_aimed_at_the_target():
    camera, target, up = np.array([0.62, 0.78, 0.55]), np.array([0.5, 0.0, 0.05]), np.eye(3)[2]
    frame = frames.look_at_frame(camera, target, up)
    rot = frame[:3, :3]
    np.testing.assert_allclose(rot.T @ rot, np.eye(3), atol=1e-12)
    assert np.linalg.det(rot) == pytest.approx(1.0)
    local = frames.to_frame(target[None], frame)[0]
    np.testing.assert_allclose(local, [0.0, 0.0, np.linalg.norm(target - camera)], atol=1e-12)
    assert rot[:, 1] @ up < 0  # image y points down
    assert abs(rot[:, 0] @ up) < 1e-12  # no roll: image x is horizontal
    with pytest.raises(ValueError, match="own position"):
        frames.look_at_frame(target, target, up)
    with pytest.raises(ValueError, match="up axis"):
        frames.look_at_frame(target + up, target, up)


def test_poses_in_a_frame_map_back_to_world():
    rng = np.random.default_rng(2)
    frame = frames.look_at_frame(np.array([0.6, -0.8, 0.5]), np.array([0.5, 0, 0]), np.eye(3)[2])
    world = frames.grasp_frames_to_network(
        rng.uniform(0, 1, (5, 3)), np.stack([random_rotation(rng) for _ in range(5)]), DEPTH
    )
    local = np.einsum("ij,gjk->gik", np.linalg.inv(frame), world)
    np.testing.assert_allclose(frames.poses_to_world(local, frame), world, atol=1e-12)
    centred = frames.world_centred_frame(world[:, :3, 3])
    np.testing.assert_allclose(
        frames.to_frame(world[:, :3, 3], centred).mean(axis=0), 0, atol=1e-12
    )


def test_table_patch_lies_on_the_plane_within_its_radius():
    plane = np.array([0.0, 0.0, 1.0, -0.02])  # z = 0.02
    centre = np.array([0.5, 0.1, 0.3])
    patch = frames.table_patch(centre, plane, 0.1, 0.005)
    np.testing.assert_allclose(patch[:, 2], 0.02, atol=1e-12)
    radial = np.linalg.norm(patch[:, :2] - centre[:2], axis=1)
    assert radial.max() <= 0.1 + 1e-12
    assert patch.shape[0] == pytest.approx(np.pi * 0.1**2 / 0.005**2, rel=0.05)


def test_visible_from_keeps_the_faces_a_camera_sees():
    rng = np.random.default_rng(3)
    box = Box((0.03, 0.05, 0.04), center=np.array([0.5, 0.0, 0.04]))
    points, normals = box.sample_surface(20000, rng)
    camera = np.array([0.62, 0.78, 0.55])
    # A convex body: a point is visible exactly when its face faces the camera.
    truth = np.einsum("ij,ij->i", normals, camera - points) > 0
    got = frames.visible_from(points, camera)
    assert np.count_nonzero(got & truth) / np.count_nonzero(truth) > 0.95
    # Faces turned away by only a few degrees pass for seen at the large sphere the harness's
    # noisy clouds need (frames.visible_from): measured 8 % of the points kept here.
    assert np.count_nonzero(got & ~truth) / np.count_nonzero(got) < 0.1


def test_seen_in_image_keeps_the_points_that_cameras_depth_measured():
    from tests.volumetric_scene import render

    rng = np.random.default_rng(4)
    box = Box((0.03, 0.05, 0.04), center=np.array([0.5, 0.0, 0.04]))
    points, _ = box.sample_surface(20000, rng)
    points = points[points[:, 2] > 1e-3]  # the table hides the bottom face
    lower, upper = box.center - box.half_extents, box.center + box.half_extents
    for camera in ([0.62, 0.78, 0.55], [0.62, -0.78, 0.55]):
        view = render(np.array(camera), [(lower, upper)])
        got = frames.seen_in_image(points, view, 0.01)
        # The camera's side (+y or -y face) and the top are its own; of the far side only the
        # points within the tolerance of a surface the camera sees in front of or behind them:
        # the top face, the +x face (the camera is at x 0.62) and the table.
        facing = np.sign(points[:, 1] - box.center[1]) == np.sign(camera[1])
        side = np.abs(np.abs(points[:, 1] - box.center[1]) - 0.05) < 1e-6
        assert got[side & facing].mean() > 0.95
        far = got & side & ~facing
        near_seen = (points[:, 2] > upper[2] - 0.01) | (points[:, 2] < 0.01)
        assert np.all(near_seen[far] | (points[far, 0] > upper[0] - 0.01))
        assert far.sum() < 0.15 * (side & ~facing).sum()
        assert got[points[:, 2] > 0.08 - 1e-6].mean() > 0.95
    # A point behind the camera, or with no depth at its pixel, is not seen.
    assert not frames.seen_in_image(np.array([[0.62, 2.0, 0.55]]), view, 0.01).any()


def test_config_file_loads_and_bad_values_are_named():
    cfg = load_contact_graspnet_config()
    assert isinstance(cfg, ContactGraspNetConfig)
    with pytest.raises(ValueError, match="confidence_threshold"):
        ContactGraspNetConfig(confidence_threshold=1.5)
    with pytest.raises(ValueError, match="max_input_points"):
        ContactGraspNetConfig(max_input_points=100)
    with pytest.raises(ConfigError, match="sideways"):
        from_dict(ContactGraspNetConfig, {"input_frame": "sideways"}, "x")


def test_without_the_extra_naming_the_planner_says_how_to_install(monkeypatch):
    from hsqbench.planner.registry import get_planner, planner_names

    assert {"contact-graspnet", "contact-graspnet-elim"} <= set(planner_names())
    monkeypatch.setitem(sys.modules, "cgn_pytorch", None)  # import cgn_pytorch -> ImportError
    for name in ("contact-graspnet", "contact-graspnet-elim"):
        with pytest.raises(RuntimeError, match=r"pip install -e '\.\[learned\]'.*make learned"):
            get_planner(name)


def test_cloud_placement_finds_the_far_contact_and_keeps_the_network_one_when_unseen():
    from hsqbench.planner.learned.width import place_on_cloud

    # Two parallel faces of a 6 cm slab, x = 0 and x = 0.06, sampled every 2 mm.
    u, v = np.meshgrid(np.arange(-0.03, 0.03, 0.002), np.arange(-0.03, 0.03, 0.002))
    face = np.column_stack([np.zeros(u.size), u.ravel(), v.ravel()])
    cloud = np.vstack([face, face + np.array([0.06, 0.0, 0.0])])
    contacts = np.array([[0.0, 0.001, 0.001], [0.06, 0.001, 0.001]])
    # The network's closing axes point either way; its poses sit 4 cm from the contact.
    closing = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    network_centres = contacts - np.array([0.04, 0.0, 0.0])
    centres, widths, found = place_on_cloud(
        cloud, contacts, closing, network_centres, 0.003, 0.006, 0.1
    )
    assert found.all()
    np.testing.assert_allclose(widths, 0.06, atol=1e-9)
    np.testing.assert_allclose(centres[:, 0], 0.03, atol=1e-9)
    # Far face unseen: the network's placement stays, its width twice the contact offset.
    centres, widths, found = place_on_cloud(
        face, contacts[:1], closing[:1], network_centres[:1], 0.003, 0.006, 0.1
    )
    assert not found.any()
    np.testing.assert_allclose(centres, network_centres[:1])
    np.testing.assert_allclose(widths, [0.08])
