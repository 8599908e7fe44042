"""The examples run as a user runs them: the CLI in a subprocess with the example planner from
its file (examples/topdown.py:TopDown) and from a pip-installed package (its entry point), two
worker processes, and the Python API script."""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOPDOWN = "examples/topdown.py:TopDown"

pytestmark = pytest.mark.skipif(
    not os.environ.get("HSQ_YCB_DIR"), reason="the quick protocol uses YCB objects (HSQ_YCB_DIR)"
)


def _run(args: list[str], env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    result = subprocess.run(
        [sys.executable, *args],
        cwd=ROOT,
        env={**os.environ, **(env or {})},
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 0, result.stderr[-3000:]
    return result


def _cli(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return _run(["-m", "hsqbench.cli", *args], env)


def _attempts(run_dir: Path) -> list[dict[str, str]]:
    with (run_dir / "attempts.csv").open(newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def topdown_run(tmp_path_factory) -> Path:
    """The example's benchmark: the quick protocol's two isolated objects, topdown and hsq."""
    run_dir = tmp_path_factory.mktemp("runs") / "topdown"
    _cli(
        *("benchmark", "--protocol", "quick", "--experiments", "isolated", "--jobs", "2"),
        *("--planners", TOPDOWN, "hsq", "--run", str(run_dir)),
    )
    return run_dir


def test_the_example_planner_runs_one_trial_from_its_file():
    out = _cli("trial", "--planner", TOPDOWN, "--object", "foam_brick", "--seed", "0").stdout
    assert "isolated trial: foam_brick, seed 0, planner topdown:" in out


def test_the_example_benchmark_runs_in_two_workers_and_records_the_planners_code(topdown_run):
    rows = _attempts(topdown_run)
    assert {(r["planner"], r["objects"]) for r in rows} == {
        (p, o) for p in ("topdown", "hsq") for o in ("tomato_soup_can", "foam_brick")
    }
    assert all(r["status"] == "ok" for r in rows), [r["detail"] for r in rows]
    meta = json.loads((topdown_run / "run.json").read_text())
    assert meta["config"]["planners"] == ["hsq", "topdown"]  # quick's own list, then the added
    source = meta["backend"]["planner_sources"]["topdown"]
    assert source["kind"] == "file" and source["file"] == str(ROOT / "examples/topdown.py")
    assert "| topdown |" in (topdown_run / "tables.md").read_text()


def test_a_pip_installed_planner_is_listed_and_benchmarked_and_joins_another_run(
    tmp_path, topdown_run
):
    package = shutil.copytree(ROOT / "examples/plugin_package", tmp_path / "src")
    target = tmp_path / "site"
    pip = ["-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation"]
    _run([*pip, "--target", str(target), str(package)])
    env = {"PYTHONPATH": os.pathsep.join([str(ROOT), str(target)])}
    listed = _cli("planners", env=env).stdout
    assert "topdown-rules" in listed and "package hsqbench-topdown-rules 0.1.0" in listed

    run_dir = tmp_path / "rules"
    _cli(
        *("benchmark", "--protocol", "quick", "--experiments", "isolated", "--jobs", "2"),
        *("--planners", "topdown-rules", "--run", str(run_dir)),
        env=env,
    )
    rows = _attempts(run_dir)
    assert {r["planner"] for r in rows} == {"topdown-rules"} and len(rows) == 2
    assert all(r["status"] == "ok" for r in rows), [r["detail"] for r in rows]
    source = json.loads((run_dir / "run.json").read_text())["backend"]["planner_sources"]
    assert source["topdown-rules"]["version"] == "0.1.0"

    # The same protocol's runs share a table (report --join), whoever made them.
    _cli("report", "--run", str(run_dir), "--join", str(topdown_run), env=env)
    table = (run_dir / "tables.md").read_text()
    assert all(f"| {p} |" in table for p in ("topdown-rules", "topdown", "hsq"))


def test_the_python_api_example_runs(tmp_path):
    out = _run(["examples/notebook_api.py", str(tmp_path / "api")]).stdout
    assert "trial: foam_brick ->" in out and "topdown" in out and "config hash" in out
