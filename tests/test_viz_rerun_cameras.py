"""One camera in a recording (hsqbench.viz.rerun_cameras): entity names without ``cam_``, depth
stored compactly, and the pinhole's principal point moved to Rerun's pixel-corner convention."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
import rerun as rr

from hsqbench.viz.rerun_cameras import camera_entity_name, depth_image, log_camera


class _Stream:
    """Collects what is logged, as (entity path, archetype)."""

    def __init__(self) -> None:
        self.logged: list[tuple[str, object]] = []

    def log(self, path: str, archetype: object) -> None:
        self.logged.append((path, archetype))


def _buffer(image, dtype) -> np.ndarray:
    raw = image.buffer.as_arrow_array().to_pylist()[0]
    return np.frombuffer(np.asarray(raw, dtype=np.uint8).tobytes(), dtype=dtype)


def test_depth_image_quantises_to_the_unit_and_falls_back_to_float():
    depth = np.array([[0.0, 0.5], [1.23456, 3.8]], dtype=np.float32)
    img = depth_image(rr, depth, 1e-4)
    buf = _buffer(img, np.uint16)
    assert buf.reshape(2, 2) * 1e-4 == pytest.approx(depth, abs=0.5e-4)
    assert buf[0] == 0  # invalid stays invalid
    far = depth_image(rr, np.array([[7.0]], dtype=np.float32), 1e-4)  # beyond 6.5535 m
    assert _buffer(far, np.float32)[0] == 7.0


def test_camera_entity_name():
    assert camera_entity_name("cam_left") == "left"
    assert camera_entity_name("overhead") == "overhead"
    assert camera_entity_name("cam_") == "cam_"


def test_a_camera_logs_its_pose_pinhole_and_depth_under_its_entity_name():
    T = np.eye(4)
    T[:3, 3] = [0.5, -0.2, 0.9]
    K = np.array([[100.0, 0.0, 31.5], [0.0, 110.0, 23.5], [0.0, 0.0, 1.0]])
    cam = SimpleNamespace(
        name="cam_left",
        T_world_camera=T,
        K=K,
        width_px=64,
        height_px=48,
        depth_m=np.full((48, 64), 0.7, dtype=np.float32),
    )
    stream = _Stream()
    log_camera(stream, rr, cam, 1e-4)
    paths = [p for p, _ in stream.logged]
    assert paths == ["world/cameras/left"] * 2 + ["world/cameras/left/depth"]
    pose, pinhole, depth = (a for _, a in stream.logged)
    assert pose.translation.as_arrow_array().to_pylist()[0] == pytest.approx([0.5, -0.2, 0.9])
    logged_K = np.array(pinhole.image_from_camera.as_arrow_array().to_pylist()[0]).reshape(3, 3).T
    np.testing.assert_allclose(logged_K[:2, 2], [32.0, 24.0])  # pixel centres to corners
    np.testing.assert_allclose(logged_K[:2, :2], K[:2, :2])
    np.testing.assert_allclose(cam.K[:2, 2], [31.5, 23.5])  # the camera's own K is untouched
    assert pinhole.resolution.as_arrow_array().to_pylist()[0] == [64.0, 48.0]
    assert _buffer(depth, np.uint16)[0] == 7000
