"""The episode's default layout (hsqbench.viz.blueprint): the scene seen from the first
camera's side, looking at the workspace floor, with each depth image and the outcome beside it;
built from what a recording holds (hsqbench.viz.rrd), so older recordings get it too."""

from __future__ import annotations

import numpy as np
import pytest
import rerun as rr
import rerun.blueprint as rrb

from hsqbench.viz.blueprint import EYE_PULLBACK, episode_blueprint, eye_position, save_blueprint
from hsqbench.viz.rrd import read_recording

CAMERA = np.array([0.62, 0.78, 0.55])
FLOOR = np.array([0.5, 0.0, 0.0])


def _views(blueprint) -> tuple[rrb.Spatial3DView, list]:
    scene, side = blueprint.root_container.contents
    return scene, side.contents


def test_the_scene_is_seen_from_the_cameras_side_with_depth_and_outcome_beside_it():
    scene, side = _views(episode_blueprint(["left", "right"], CAMERA, FLOOR))
    assert isinstance(scene, rrb.Spatial3DView) and scene.origin == "world"
    eye = scene.properties["EyeControls3D"]
    position = np.asarray(eye.position.as_arrow_array().to_pylist()[0])
    target = np.asarray(eye.look_target.as_arrow_array().to_pylist()[0])
    np.testing.assert_allclose(position, FLOOR + EYE_PULLBACK * (CAMERA - FLOOR), atol=1e-6)
    np.testing.assert_allclose(target, FLOOR, atol=1e-6)
    kinds = [(type(v).__name__, v.origin) for v in side]
    assert kinds[:3] == [
        ("Spatial2DView", "world/cameras/left"),
        ("Spatial2DView", "world/cameras/right"),
        ("TextDocumentView", "outcome"),
    ]


def test_without_camera_or_floor_the_viewer_keeps_its_own_eye():
    scene, side = _views(episode_blueprint(["left"]))
    assert "EyeControls3D" not in scene.properties and len(side) == 4


def test_eye_position_is_on_the_cameras_line():
    eye = eye_position(CAMERA, FLOOR)
    assert np.linalg.norm(eye - FLOOR) == pytest.approx(
        EYE_PULLBACK * np.linalg.norm(CAMERA - FLOOR)
    )
    assert np.allclose(np.cross(eye - FLOOR, CAMERA - FLOOR), 0.0)


def test_a_recording_gives_the_cameras_and_floor_of_its_layout(tmp_path):
    path = tmp_path / "episode.rrd"
    rec = rr.RecordingStream("hsqbench")
    rec.save(path)
    rec.log("world/workspace", rr.Boxes3D(mins=[[0.3, -0.2, 0.0]], sizes=[[0.4, 0.4, 0.3]]))
    rec.set_time("sim_time", duration=0.0)
    for name, y in (("right", -0.78), ("left", 0.78)):
        rec.log(f"world/cameras/{name}", rr.Transform3D(translation=[0.62, y, 0.55]))
        rec.log(f"world/cameras/{name}/depth", rr.DepthImage(np.ones((4, 4), np.uint16)))
    rec.flush()
    rec.disconnect()
    summary = read_recording(path)
    assert summary.camera_names == ["left", "right"]
    assert sorted(summary.camera_positions) == ["world/cameras/left", "world/cameras/right"]
    np.testing.assert_allclose(summary.camera_positions["world/cameras/right"], [0.62, -0.78, 0.55])
    np.testing.assert_allclose(summary.floor_centre, [0.5, 0.0, 0.0], atol=1e-6)
    rbl = save_blueprint(episode_blueprint(summary.camera_names), tmp_path / "episode.rbl")
    from rerun.chunk import RrdReader

    [store] = RrdReader(rbl).blueprints()
    assert store.application_id == "hsqbench"
