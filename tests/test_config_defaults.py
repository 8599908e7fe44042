"""Every config class's built-in defaults equal its file in ``configs/`` (one test per file),
so "None gives the built-in defaults" means the same settings as the shipped YAML."""

from __future__ import annotations

import dataclasses
import importlib

import pytest

from hsqbench.config import load_config
from hsqbench.settings import CONFIG_DIR

#: File -> the class it configures.
CLASSES = {
    "assets": "hsqbench.assets.config:AssetsConfig",
    "baselines": "hsqbench.planner.baselines.config:BaselinesConfig",
    "clutter": "hsqbench.sim.clutter.config:ClutterConfig",
    "contact_graspnet": "hsqbench.planner.learned.config:ContactGraspNetConfig",
    "gripper": "hsqbench.planner.gripper:GripperModel",
    "hold": "tests.hold_rig:HoldConfig",
    "oracle": "hsqbench.planner.oracle:OracleConfig",
    "perception": "hsqbench.sim.perception:PerceptionConfig",
    "physics": "hsqbench.sim.physics:PhysicsConfig",
    "planner": "hsqbench.planner.hsq.config:PlannerConfig",
    "robot": "hsqbench.sim.robot:RobotConfig",
    "scene": "hsqbench.sim.scene:SceneConfig",
    "trial": "hsqbench.sim.trial:TrialConfig",
    "viewer": "hsqbench.viz.config:ViewerConfig",
    "volumetric": "hsqbench.planner.learned.volumetric_config:VolumetricConfig",
}
#: Files that are not one class's defaults: variants that extend another file, and the list of
#: canonical runs (hsqbench.experiment.canonical, tested in its own test). The protocols
#: (configs/protocols/, whose object lists and sizes are the experiment itself) are tested in
#: tests/test_experiment_config.py.
NOT_DEFAULTS = {
    "canonical",
    "clutter_arm",
    "clutter_arm_bin",
    "clutter_arm_cameras",
    "clutter_ring",
    "scene_resting",
    "trial_clutter",
    "trial_clutter_arm",
    "trial_clutter_arm_bin",
    "trial_clutter_arm_cameras",
    "trial_clutter_ring",
    "trial_resting",
}


def _class(spec: str):
    module, name = spec.split(":")
    return getattr(importlib.import_module(module), name)


def test_every_config_file_is_covered() -> None:
    files = {p.stem for p in CONFIG_DIR.glob("*.yaml")}
    assert files == set(CLASSES) | NOT_DEFAULTS


@pytest.mark.parametrize("name", sorted(CLASSES))
def test_defaults_equal_the_file(name: str) -> None:
    cls = _class(CLASSES[name])
    loaded = load_config(cls, name)
    default = cls()
    if name == "assets":
        # The library's object lists are data, not settings: the empty default is an empty
        # library, and the trial config tree's default loads configs/assets.yaml itself.
        loaded = dataclasses.replace(
            loaded,
            download=dataclasses.replace(loaded.download, objects=()),
            procedural=dataclasses.replace(loaded.procedural, objects=()),
        )
    assert default == loaded
