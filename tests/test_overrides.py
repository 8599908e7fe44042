"""Config overrides (hsqbench.overrides): dotted paths checked against the dataclasses."""

from __future__ import annotations

import pytest

from hsqbench.config import load_config_data
from hsqbench.errors import ConfigError
from hsqbench.overrides import apply_overrides, parse_assignments
from hsqbench.sim.perception_config import PerceptionConfig
from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.robot import RobotConfig
from hsqbench.sim.trial import load_trial_config


def tree(overrides):
    """The trial's config tree (configs/trial.yaml, every file it names read in) with overrides."""
    return load_trial_config("trial", overrides)


def test_nested_field_list_index_and_whole_value():
    data = load_config_data("perception")
    out = apply_overrides(
        data, {"tof.sigma_quad_per_m": 0.004, "sensor_model": "calibration"}, PerceptionConfig
    )
    assert out["tof"]["sigma_quad_per_m"] == 0.004 and out["sensor_model"] == "calibration"
    assert data["tof"]["sigma_quad_per_m"] == 0.001  # the input is not changed
    assert out["tof"]["dropout_prob"] == data["tof"]["dropout_prob"]  # siblings kept
    robot = tree({"robot.pads.friction.0": 0.5}).robot
    assert robot.pads.friction == (0.5, 0.0065, 0.002)  # only the sliding component
    scene = tree({"scene.depth_cameras.names": ["cam_left"]}).scene
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
        tree({"perception.tof.sigma_quad": 0.1})
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
        tree({"perception.voxel_m": "big"})


def test_trial_tree_applies_own_fields_and_nested_parts_and_checks_paths_up_front():
    tc = tree(
        {"max_ranks": 7, "perception.voxel_m": 0.004, "planners.hsq.grasp.max_tilt_deg": 20.0}
    )
    assert tc.max_ranks == 7 and tc.perception.voxel_m == 0.004
    assert tc.planners.hsq.grasp.max_tilt_deg == 20.0
    plain = tree(None)
    assert plain.perception.voxel_m != 0.004 and plain.max_ranks != 7
    with pytest.raises(ConfigError, match=r"scene\.depth_camera"):
        tree({"scene.depth_camera.names": ["cam_left"]})


def test_overrides_enter_the_fingerprint_and_are_picklable():
    import pickle

    from hsqbench.experiment.backend import SimBackend

    plain = SimBackend("trial").fingerprint()
    assert "overrides" not in plain
    backend = SimBackend("trial", overrides=(("perception.tof.sigma_quad_per_m", 0.002),))
    printed = backend.fingerprint()
    assert printed["overrides"] == {"perception.tof.sigma_quad_per_m": 0.002}
    assert printed["trial_config"]["perception"]["tof"]["sigma_quad_per_m"] == 0.002
    assert plain["trial_config"]["perception"]["tof"]["sigma_quad_per_m"] == 0.001
    again = pickle.loads(pickle.dumps(backend))
    assert again.fingerprint() == printed


def test_object_mass_scale_scales_mass_and_inertia_of_the_objects_only():
    from hsqbench.sim.scene import build_scene

    def body(scale):
        physics = tree({"physics.object_mass_scale": scale}).physics
        model, _, info = build_scene("isolated", "proc_box", seed=0, physics_config=physics)
        b = info.object_body_ids["proc_box"]
        return model.body_mass[b], model.body_inertia[b].copy(), model.body_mass.sum()

    m1, i1, total1 = body(1.0)
    m2, i2, total2 = body(2.5)
    assert m2 == pytest.approx(2.5 * m1) and i2 == pytest.approx(2.5 * i1)
    assert total2 - total1 == pytest.approx(1.5 * m1)  # nothing else got heavier
    with pytest.raises(ConfigError, match="object_mass_scale must be positive"):
        tree({"physics.object_mass_scale": 0.0})


def test_command_line_assignments_are_read_as_yaml():
    assert parse_assignments(["ik.restarts=4", "scene.depth_cameras.names=[cam_left]"]) == {
        "ik.restarts": 4,
        "scene.depth_cameras.names": ["cam_left"],
    }
    for bad in ("ik.restarts", "=4"):
        with pytest.raises(ConfigError, match=r"--set .*write KEY=VALUE"):
            parse_assignments([bad])
