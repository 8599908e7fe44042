"""Config overrides (hsqbench.overrides): dotted paths checked against the dataclasses."""

from __future__ import annotations

import pytest

from hsqbench.config import ConfigError, load_config_data
from hsqbench.overrides import apply_overrides, load_part, load_trial_tree, split_overrides
from hsqbench.sim.perception_config import PerceptionConfig
from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.robot import RobotConfig
from hsqbench.sim.trial import TrialConfig


def test_nested_field_list_index_and_whole_value():
    data = load_config_data("perception")
    out = apply_overrides(
        data, {"tof.sigma_quad_per_m": 0.004, "sensor_model": "calibration"}, PerceptionConfig
    )
    assert out["tof"]["sigma_quad_per_m"] == 0.004 and out["sensor_model"] == "calibration"
    assert data["tof"]["sigma_quad_per_m"] == 0.001  # the input is not changed
    assert out["tof"]["dropout_prob"] == data["tof"]["dropout_prob"]  # siblings kept
    robot = load_part("robot", "robot", {"robot.pads.friction.0": 0.5})
    assert robot.pads.friction == (0.5, 0.0065, 0.002)  # only the sliding component
    scene = load_part("scene", "scene", {"scene.depth_cameras.names": ["cam_left"]})
    assert scene.depth_cameras.names == ("cam_left",)


def test_a_key_missing_from_the_yaml_is_filled_from_the_dataclass_default():
    # physics.yaml has no such key: the default's value is completed, then the index is set
    out = apply_overrides({}, {"objects.friction.0": 0.3}, PhysicsConfig)
    assert out["objects"]["friction"][0] == 0.3
    assert out["objects"]["friction"][1:] == list(PhysicsConfig().objects.friction[1:])


def test_unknown_key_names_the_path_and_the_valid_keys():
    with pytest.raises(
        ConfigError, match=r"perception\.tof\.sigma_quad.*valid keys: .*sigma_quad_per_m"
    ):
        load_part("perception", "perception", {"perception.tof.sigma_quad": 0.1})
    with pytest.raises(ConfigError, match=r"'pad' is not a key of the top level.*'pads'"):
        apply_overrides({}, {"pad.friction.0": 1.0}, RobotConfig)


def test_bad_index_and_bad_value_are_errors():
    with pytest.raises(ConfigError, match=r"'3' is not an index.*0 to 2"):
        apply_overrides({}, {"pads.friction.3": 1.0}, RobotConfig)
    with pytest.raises(ConfigError, match="no keys"):
        apply_overrides({}, {"voxel_m.x": 1.0}, PerceptionConfig)
    with pytest.raises(ConfigError, match="a path is keys"):
        apply_overrides({}, {"tof..x": 1.0}, PerceptionConfig)
    with pytest.raises(ConfigError, match="expected a number"):
        load_part("perception", "perception", {"perception.voxel_m": "big"})


def test_trial_tree_applies_own_fields_and_checks_part_paths_up_front():
    tc = load_trial_tree(TrialConfig, "trial", {"max_ranks": 7, "perception.voxel_m": 0.004})
    assert tc.max_ranks == 7
    assert tc.overrides == {"max_ranks": 7, "perception.voxel_m": 0.004}
    assert load_part(tc.perception, "perception", tc.overrides).voxel_m == 0.004
    with pytest.raises(ConfigError, match=r"scene\.depth_camera"):
        load_trial_tree(TrialConfig, "trial", {"scene.depth_camera.names": ["cam_left"]})
    own, parts = split_overrides({"perception": "perception", "robot.pads.condim": 6, "a.b": 1})
    assert own == {"perception": "perception", "a.b": 1}
    assert parts == {"robot": {"pads.condim": 6}}


def test_overrides_enter_the_fingerprint_and_are_picklable():
    import pickle

    from hsqbench.experiment.backend import SimBackend

    plain = SimBackend("trial").fingerprint()
    assert "overrides" not in plain["trial_config"]  # old runs keep their hash
    backend = SimBackend("trial", overrides={"perception.tof.sigma_quad_per_m": 0.002})
    printed = backend.fingerprint()
    assert printed["trial_config"]["overrides"] == {"perception.tof.sigma_quad_per_m": 0.002}
    assert printed["configs"]["perception"]["tof"]["sigma_quad_per_m"] == 0.002
    assert plain["configs"]["perception"]["tof"]["sigma_quad_per_m"] == 0.001
    again = pickle.loads(pickle.dumps(backend))
    assert again.fingerprint() == printed


def test_object_mass_scale_scales_mass_and_inertia_of_the_objects_only():
    from hsqbench.sim.scene import build_scene

    def body(scale):
        physics = load_part("physics", "physics", {"physics.object_mass_scale": scale})
        model, _, info = build_scene("isolated", "proc_box", seed=0, physics_config=physics)
        b = info.object_body_ids["proc_box"]
        return model.body_mass[b], model.body_inertia[b].copy(), model.body_mass.sum()

    m1, i1, total1 = body(1.0)
    m2, i2, total2 = body(2.5)
    assert m2 == pytest.approx(2.5 * m1) and i2 == pytest.approx(2.5 * i1)
    assert total2 - total1 == pytest.approx(1.5 * m1)  # nothing else got heavier
    with pytest.raises(ConfigError, match="object_mass_scale must be positive"):
        load_part("physics", "physics", {"physics.object_mass_scale": 0.0})
