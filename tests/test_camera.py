"""Pinhole geometry of MuJoCo cameras (hsqbench.sim.camera). Rendering checks are in
tests/test_perception.py."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from hsqbench.sim.camera import (
    OPTICAL_TO_MUJOCO,
    backproject,
    box_roi,
    camera_intrinsics,
    camera_pose,
    crop_intrinsics,
    intrinsics_from_fovy,
    invert_pose,
    project,
    transform_points,
)


def test_intrinsics_follow_fovy_and_image_centre():
    K = intrinsics_from_fovy(90.0, 640, 480)
    # tan(45 deg) = 1: the image's half height (240 px) spans one unit of depth.
    assert K[0, 0] == pytest.approx(240.0)
    assert K[1, 1] == pytest.approx(240.0)
    assert K[0, 2] == pytest.approx(319.5)
    assert K[1, 2] == pytest.approx(239.5)


@pytest.mark.parametrize("fovy", [0.0, 180.0, -10.0])
def test_intrinsics_refuse_impossible_fovy(fovy):
    with pytest.raises(ValueError, match="fovy"):
        intrinsics_from_fovy(fovy, 64, 48)


def test_backproject_then_project_returns_the_pixels():
    K = intrinsics_from_fovy(60.0, 40, 30)
    rng = np.random.default_rng(0)
    depth = rng.uniform(0.5, 2.0, size=(30, 40))
    pts = backproject(depth, K)
    assert np.allclose(pts[..., 2], depth)
    uv = project(pts.reshape(-1, 3), K)
    v, u = np.mgrid[0:30, 0:40]
    assert np.allclose(uv, np.column_stack([u.ravel(), v.ravel()]))
    # Right of the centre is +x, below it is +y (optical frame, rows grow downwards).
    assert pts[15, 39, 0] > 0 and pts[29, 20, 1] > 0


def test_crop_intrinsics_keep_the_rays():
    K = intrinsics_from_fovy(60.0, 40, 30)
    depth = np.full((30, 40), 1.3)
    full = backproject(depth, K)
    sub = backproject(depth[5:20, 10:33], crop_intrinsics(K, 5, 10))
    assert np.allclose(sub, full[5:20, 10:33])


def _camera_model(quat: str) -> tuple[mujoco.MjModel, mujoco.MjData]:
    xml = f"""<mujoco><worldbody>
      <camera name="c" pos="0.1 -0.2 0.7" quat="{quat}" fovy="50" resolution="64 48"/>
    </worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


def test_camera_pose_is_the_optical_frame_of_the_mujoco_camera():
    _, data = _camera_model("0.9 0.3 -0.2 0.25")
    T = camera_pose(data, 0)
    R = T[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
    assert np.allclose(T[:3, 3], [0.1, -0.2, 0.7])
    mj = data.cam_xmat[0].reshape(3, 3)
    # Optical z (forward) is MuJoCo's -z, optical y (down) is MuJoCo's -y, x is shared.
    assert np.allclose(R[:, 2], -mj[:, 2])
    assert np.allclose(R[:, 1], -mj[:, 1])
    assert np.allclose(R[:, 0], mj[:, 0])
    assert np.allclose(OPTICAL_TO_MUJOCO @ OPTICAL_TO_MUJOCO, np.eye(3))


def test_camera_intrinsics_read_the_model_and_refuse_missing_resolution():
    model, _ = _camera_model("1 0 0 0")
    K, w, h = camera_intrinsics(model, 0)
    assert (w, h) == (64, 48)
    assert np.allclose(K, intrinsics_from_fovy(50.0, 64, 48))
    bare = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><camera name="c" fovy="50"/></worldbody></mujoco>'
    )
    with pytest.raises(ValueError, match="resolution"):
        camera_intrinsics(bare, 0)


def test_pose_inverse_and_transform_round_trip():
    _, data = _camera_model("0.9 0.3 -0.2 0.25")
    T = camera_pose(data, 0)
    pts = np.random.default_rng(1).normal(size=(50, 3))
    assert np.allclose(transform_points(invert_pose(T), transform_points(T, pts)), pts)


def test_box_roi_contains_the_projected_box_and_falls_back_to_the_full_image():
    K = intrinsics_from_fovy(60.0, 200, 150)
    T = np.eye(4)  # camera at the origin looking along +z (optical frame = world)
    lo, hi = np.array([-0.1, -0.05, 1.0]), np.array([0.05, 0.1, 1.2])
    v0, v1, u0, u1 = box_roi(T, K, 200, 150, lo, hi, pad_px=2)
    corners = np.array(
        [[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (1.0, 1.2)]
    )
    uv = project(corners, K)
    assert np.all(uv[:, 0] >= u0) and np.all(uv[:, 0] < u1)
    assert np.all(uv[:, 1] >= v0) and np.all(uv[:, 1] < v1)
    assert (v1 - v0) * (u1 - u0) < 0.5 * 200 * 150
    behind = box_roi(T, K, 200, 150, lo - [0, 0, 2.0], hi, pad_px=2)
    assert behind == (0, 150, 0, 200)
