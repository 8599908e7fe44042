"""Plugin planners (loading: hsqbench.planner.plugins; registering: the registry): specs
(module:Name, file.py:Name) and entry points, their errors, their journey to worker processes,
and their place in a run's identity."""

from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

from hsqbench.experiment.backend import SimBackend
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.runner import run_benchmark
from hsqbench.planner import plugins, registry
from hsqbench.planner.api import PlanningContext
from tests.fake_backend import FakeBackend

PLANNER = """
import numpy as np
from hsqbench.planner.api import PlanResult
from hsqbench.planner.base import PlannerBase
from hsqbench.planner.grasp import Grasp

class {cls}(PlannerBase):
    name = "{name}"

    def stages(self, clean, context):
        c = clean.points.mean(axis=0)
        return PlanResult(grasps=[Grasp(c, np.diag([1.0, -1.0, -1.0]), 0.04, 1.0)])
"""


@pytest.fixture(autouse=True)
def _fresh_registry(monkeypatch):
    """Each test registers its plugins in a registry of its own."""
    monkeypatch.setattr(registry, "_SPECS", {})
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))


def _write(tmp_path: Path, cls: str = "Mine", name: str = "mine", file: str = "mine.py") -> Path:
    path = tmp_path / file
    path.write_text(PLANNER.format(cls=cls, name=name))
    return path


def test_a_file_spec_registers_under_the_planners_name_and_plans(tmp_path):
    path = _write(tmp_path)
    name = registry.resolve_planner(f"{path}:Mine")
    assert name == "mine" and "mine" in registry.planner_names()
    cloud = np.random.default_rng(0).normal(0.0, 0.01, (200, 3)) + np.array([0.5, 0.0, 0.05])
    result = registry.get_planner("mine").plan(cloud, PlanningContext())
    assert result.planner == "mine" and len(result.grasps) == 1
    assert result.timings["cleaning"] >= 0.0 and "total" in result.timings  # the base's cleaning
    source = registry.source_of("mine")
    assert source.kind == "file" and source.file == str(path.resolve())
    assert source.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert registry.resolve_planner(f"{path}:Mine") == "mine"  # again: the same registration


def test_a_module_spec_is_found_in_the_current_folder(tmp_path, monkeypatch):
    _write(tmp_path, file="my_planner_mod.py")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.path", [p for p in __import__("sys").path if p not in ("", ".")])
    assert registry.resolve_planner("my_planner_mod:Mine") == "mine"
    assert registry.source_of("mine").kind == "module"


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("nowhere/missing.py:Mine", r"no file nowhere/missing\.py"),
        ("{path}:Mien", r"has no 'Mien' \(did you mean 'Mine'\?\); its planner classes: Mine"),
        ("{path}:", r"must be module:Name or path/to/file\.py:Name"),
        ("no_such_module_xyz:Mine", r"importing no_such_module_xyz failed: ModuleNotFoundError"),
    ],
)
def test_bad_specs_say_what_is_wrong(tmp_path, spec, message):
    path = _write(tmp_path)
    with pytest.raises(plugins.PluginError, match=message):
        registry.resolve_planner(spec.format(path=path))


def test_a_file_without_its_class_names_the_classes_it_holds(tmp_path):
    """`--planner mine.py` (the class forgotten) listed every built-in planner instead."""
    path = _write(tmp_path)
    with pytest.raises(
        plugins.PluginError, match=rf"is a file: name the class too, as {path}:Mine"
    ):
        registry.resolve_planner(str(path))
    with pytest.raises(plugins.PluginError, match=r"needs its class too .* there is no file"):
        registry.resolve_planner(str(tmp_path / "absent.py"))


def test_a_name_taken_by_a_built_in_planner_is_refused(tmp_path):
    path = _write(tmp_path, name="hsq")
    with pytest.raises(plugins.PluginError, match=r"'hsq' .* is taken .* set another `name`"):
        registry.resolve_planner(f"{path}:Mine")


def test_a_misspelt_planner_gets_the_closest_name():
    with pytest.raises(ValueError, match=r"unknown planner 'hqs' \(did you mean 'hsq'\?\)"):
        registry.resolve_planner("hqs")


def test_a_planner_without_its_stages_names_the_missing_method(tmp_path):
    path = tmp_path / "half.py"
    path.write_text(
        "from hsqbench.planner.base import PlannerBase\n\nclass Half(PlannerBase):\n    name = 'half'\n"
    )
    registry.resolve_planner(f"{path}:Half")
    with pytest.raises(plugins.PluginError, match=r"planner .*Half.* cannot be built: .*stages"):
        registry.get_planner("half")


def _install_entry_point(tmp_path: Path, monkeypatch) -> None:
    """A package on sys.path with an ``hsqbench.planners`` entry point (as pip installs it)."""
    _write(tmp_path, cls="Installed", name="installed", file="installed_pkg.py")
    info = tmp_path / "installed_pkg-1.2.3.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: installed-pkg\nVersion: 1.2.3\n")
    (info / "entry_points.txt").write_text(
        "[hsqbench.planners]\ninstalled = installed_pkg:Installed\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))


def test_an_installed_entry_point_is_listed_built_and_traced_to_its_package(tmp_path, monkeypatch):
    _install_entry_point(tmp_path, monkeypatch)
    assert "installed" in registry.planner_names()
    assert registry.get_planner("installed").name == "installed"
    source = registry.source_of("installed")
    assert (source.kind, source.distribution, source.version) == (
        "entry-point",
        "installed-pkg",
        "1.2.3",
    )
    assert source.sha256 == hashlib.sha256((tmp_path / "installed_pkg.py").read_bytes()).hexdigest()
    assert registry.source_of("hsq") is None  # hsqbench's own planners are no plugins


def test_spec_planners_travel_with_the_backend_to_a_fresh_process(tmp_path, monkeypatch):
    path = _write(tmp_path)
    registry.resolve_planner(f"{path}:Mine")
    state = pickle.dumps(SimBackend())
    # A worker knows nothing of the parent's registrations.
    monkeypatch.setattr(registry, "_SPECS", {})
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))
    del registry._FACTORIES["mine"]
    worker_backend = pickle.loads(state)
    assert "mine" not in registry.planner_names()
    worker_backend._register_plugins()
    assert registry.get_planner("mine").name == "mine"


SMALL = ExperimentConfig(
    planners=("hsq",),
    seeds=(0,),
    isolated=IsolatedConfig(objects=("mug",), attempts_per_object=1),
    packed=PackedConfig(enabled=False, objects=("mug",), objects_per_round=1),
)


def test_a_runs_identity_names_its_plugins_code(tmp_path):
    path = _write(tmp_path)
    name = registry.resolve_planner(f"{path}:Mine")
    plain = run_benchmark(SMALL, tmp_path / "plain", backend=FakeBackend(), progress=False)
    assert "planner_sources" not in json.loads((tmp_path / "plain/run.json").read_text())["backend"]

    config = ExperimentConfig(**{**SMALL.__dict__, "planners": ("hsq", name)})
    mine = run_benchmark(config, tmp_path / "mine", backend=FakeBackend(), progress=False)
    recorded = json.loads((tmp_path / "mine/run.json").read_text())["backend"]["planner_sources"]
    assert recorded["mine"]["file"] == str(path.resolve())
    assert recorded["mine"]["sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()

    path.write_text(path.read_text() + "\n# edited\n")
    registry._SPECS["mine"] = plugins.load_spec(f"{path}:Mine")[1]
    edited = run_benchmark(config, tmp_path / "edited", backend=FakeBackend(), progress=False)
    assert len({plain.config_hash, mine.config_hash, edited.config_hash}) == 3
