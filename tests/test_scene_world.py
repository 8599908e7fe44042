"""The static world as MJCF (scenes/*.xml): the files compile, and the scene composed from them
is the model the harness built in code before (tests/data/scene_reference.json)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import mujoco
import numpy as np
import pytest

from hsqbench.settings import SCENES_DIR
from hsqbench.sim.physics import load_physics_config
from hsqbench.sim.robot import load_robot_config
from hsqbench.sim.scene import compose_scene, load_scene_config, world_path
from hsqbench.sim.scene.world import come_to_rest, settle
from tests.scene_reference import model_fingerprint

REFERENCE = Path(__file__).parent / "data" / "scene_reference.json"
#: Cameras only the learned_views sweep uses (configs/protocols/sweeps/learned_views.yaml).
NEAR_CAMERAS = ("cam_near_left", "cam_near_right")


@pytest.mark.parametrize("name", sorted(p.name for p in SCENES_DIR.glob("*.xml")))
def test_every_scene_file_compiles(name: str) -> None:
    model = mujoco.MjModel.from_xml_path(str(SCENES_DIR / name))
    assert model.ngeom + model.ncam + model.nlight + model.ntex > 0


def test_the_world_has_its_parts() -> None:
    model = mujoco.MjModel.from_xml_path(str(world_path(load_scene_config())))
    names = {model.geom(i).name for i in range(model.ngeom)}
    assert {"floor", "table", "bin/bottom", "bin/wall_x-", "bin/wall_y+"} <= names
    cameras = [model.camera(i).name for i in range(model.ncam)]
    assert cameras == ["cam_left", "cam_right", "viewer", *NEAR_CAMERAS]
    assert model.nlight == 2


def test_the_composed_scene_is_the_model_built_in_code_before() -> None:
    spec = compose_scene([], [], load_scene_config(), load_robot_config(), load_physics_config())
    now = model_fingerprint(spec.compile())
    before = json.loads(REFERENCE.read_text())
    assert now.keys() == before.keys()
    # The cameras added since (learned_views sweep only) come after the reference's, which keep
    # their ids and values.
    n_cam = len(before["camera_names"])
    assert now["camera_names"][n_cam:] == list(NEAR_CAMERAS)
    for key in now:
        if key.startswith("cam"):
            now[key] = now[key][:n_cam]
    for key, value in before.items():
        if isinstance(value, list) and value and not isinstance(value[0], str):
            np.testing.assert_allclose(
                np.asarray(now[key]), np.asarray(value), atol=1e-9, err_msg=key
            )
        else:
            assert now[key] == value, key


def test_the_table_and_bin_get_the_table_contact_parameters() -> None:
    physics = load_physics_config()
    spec = compose_scene([], [], load_scene_config(), load_robot_config(), physics)
    model = spec.compile()
    for name in ("table", "bin/bottom", "bin/wall_x+"):
        np.testing.assert_allclose(model.geom(name).friction, physics.table.friction)


def test_a_missing_world_file_is_named(tmp_path) -> None:
    import dataclasses

    cfg = dataclasses.replace(load_scene_config(), world=str(tmp_path / "nowhere.xml"))
    with pytest.raises(FileNotFoundError, match=r"nowhere\.xml does not exist"):
        world_path(cfg)


ROLLING = """
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1" friction="0.8 0.005 0.0001"/>
    <body name="can" pos="0 0 0.03" euler="90 0 0">
      <freejoint/>
      <geom type="cylinder" size="0.03 0.05" mass="0.2"/>
    </body>
  </worldbody>
</mujoco>
"""


def _rolling_can() -> tuple[mujoco.MjModel, mujoco.MjData, np.ndarray]:
    model = mujoco.MjModel.from_xml_string(ROLLING)
    data = mujoco.MjData(model)
    data.qvel[0] = 0.05  # rolling along x at 5 cm/s: the cylinder's axis is y
    data.qvel[4] = 0.05 / 0.03
    return model, data, np.array([model.body("can").id])


def test_a_rolling_object_is_brought_to_rest_where_plain_settling_leaves_it_rolling() -> None:
    physics = load_physics_config()
    model, data, ids = _rolling_can()
    assert settle(model, data, ids, physics)[1] > physics.settle_speed_mps  # no rolling friction
    model, data, ids = _rolling_can()
    t, speed = come_to_rest(model, data, ids, physics)
    assert speed < physics.settle_speed_mps
    assert (
        physics.settle_time_s
        < t
        <= physics.settle_time_s + physics.rest_checks * (physics.rest_check_s + model.opt.timestep)
    )
    at_rest = data.xpos[ids[0]].copy()
    for _ in range(500):  # and it stays there
        mujoco.mj_step(model, data)
    assert np.linalg.norm(data.xpos[ids[0]] - at_rest) < 1e-3


def test_a_scene_already_at_rest_is_not_touched_again() -> None:
    physics = load_physics_config()
    model, data, ids = _rolling_can()
    data.qvel[:] = 0.0
    t, speed = come_to_rest(model, data, ids, physics)
    assert speed < physics.settle_speed_mps and t < physics.settle_time_s


def test_rest_checks_must_be_sensible() -> None:
    with pytest.raises(ValueError, match="rest_check_s"):
        dataclasses.replace(load_physics_config(), rest_check_s=0.0)
    with pytest.raises(ValueError, match="rest_checks"):
        dataclasses.replace(load_physics_config(), rest_checks=-1)
