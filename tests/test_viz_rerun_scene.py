"""The static part of a recording (hsqbench.viz.rerun_scene): each body's entity path (object,
robot link or other body) and which bodies the recorder must follow."""

from __future__ import annotations

from types import SimpleNamespace

import mujoco
import pytest
import rerun as rr

from hsqbench.viz.config import load_viewer_config
from hsqbench.viz.rerun_scene import body_entity_path, log_scene


def _model() -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5, 0.5, 0.02])
    link = spec.worldbody.add_body(name="panda/link0", pos=[0.0, 0.0, 0.1])  # welded
    link.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0])
    box = spec.worldbody.add_body(name="obj_0", pos=[0.3, 0.0, 0.1])
    box.add_freejoint()
    box.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.02, 0.02, 0.02])
    other = spec.worldbody.add_body(name="", pos=[0.0, 0.3, 0.1])
    other.add_freejoint()
    other.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.03, 0, 0])
    return spec.compile()


class _Stream:
    def __init__(self) -> None:
        self.logged: list[tuple[str, object, bool]] = []

    def log(self, path: str, archetype: object, static: bool = False) -> None:
        self.logged.append((path, archetype, static))

    def send_recording_name(self, name: str) -> None:
        self.name = name

    def send_blueprint(self, blueprint: object) -> None:
        self.blueprint = blueprint


INFO = SimpleNamespace(
    kind="isolated",
    objects=["my box"],
    seed=3,
    object_body_ids={"my box": 2},
    robot_prefix="panda/",
)


def test_bodies_are_named_as_objects_robot_links_or_plain_bodies():
    model = _model()
    assert body_entity_path(rr, model, INFO, 1) == "world/robot/link0"
    assert body_entity_path(rr, model, INFO, 2) == r"world/objects/my\ box"
    assert body_entity_path(rr, model, INFO, 3) == "world/bodies/3"  # unnamed: its id


def test_the_scene_is_static_and_only_free_bodies_are_followed():
    model = _model()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    stream = _Stream()
    tracked = log_scene(stream, rr, load_viewer_config(), model, data, INFO)
    assert tracked == {2: r"world/objects/my\ box", 3: "world/bodies/3"}
    assert stream.name == "isolated my box seed 3"
    assert all(static for _, _, static in stream.logged)
    logged = {path for path, _, _ in stream.logged}
    assert {"world", "scene", "world/scene", "world/robot/link0"} <= logged
    assert "world/workspace" not in logged  # no workspace in the info
    poses = [a for p, a, _ in stream.logged if p == "world/robot/link0" and hasattr(a, "mat3x3")]
    assert len(poses) == 1  # the welded link's one static pose
    assert poses[0].translation.as_arrow_array().to_pylist()[0] == pytest.approx([0, 0, 0.1])
