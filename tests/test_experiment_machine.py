"""run.json's machine record: CPU model, cores and the versions of the packages behind the numbers."""

from __future__ import annotations

import json
from importlib import metadata

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.machine import _requirement_name, machine_info, package_versions
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend


def test_requirement_names_drop_versions_markers_and_comments() -> None:
    assert _requirement_name("mujoco>=3.3") == "mujoco"
    assert _requirement_name("fast-simplification>=0.2") == "fast-simplification"
    assert _requirement_name("ray[default]>=2.9 ; extra == 'ray'") == "ray"
    assert _requirement_name("numpy") == "numpy"


def test_versions_are_the_installed_ones_of_every_dependency() -> None:
    versions = package_versions()
    for name in ("mujoco", "numpy", "scipy", "coacd", "trimesh", "scikit-learn"):
        assert versions[name] == metadata.version(name)
    assert "pytest" not in versions  # a dev extra, not behind the numbers


def test_machine_names_the_cpu_and_cores() -> None:
    info = machine_info()
    assert info["cpu_model"] and info["cpu_model"] != "unknown"
    assert 1 <= info["usable_cores"] <= info["cpus"]
    assert info["python"].count(".") == 2


def test_run_json_records_the_machine_of_the_run_and_of_each_session(tmp_path) -> None:
    config = ExperimentConfig(
        planners=("a",),
        isolated=IsolatedConfig(objects=("mug",), attempts_per_object=1),
        packed=PackedConfig(enabled=False),
    )
    run_dir = tmp_path / "r"
    run_benchmark(config, run_dir, backend=FakeBackend(), progress=False)
    run_benchmark(config, run_dir, backend=FakeBackend(), resume=True, progress=False)
    meta = json.loads((run_dir / "run.json").read_text())
    assert meta["machine"]["packages"]["mujoco"] == metadata.version("mujoco")
    assert meta["machine"]["cpu_model"]
    assert [s["machine"]["packages"]["numpy"] for s in meta["sessions"]] == [
        metadata.version("numpy")
    ] * 2
