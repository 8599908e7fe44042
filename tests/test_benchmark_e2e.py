"""`make benchmark`'s path end to end: the quick protocol through the real simulator.

Runs the CLI in a subprocess with two worker processes (the parallel path a user gets), then
resumes the finished run to check that nothing is run or counted twice.
"""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hsqbench.experiment.config import load_experiment_config
from hsqbench.experiment.seeds import build_trials
from hsqbench.sim.outcome import Outcome

pytestmark = pytest.mark.skipif(
    not os.environ.get("HSQ_YCB_DIR"), reason="the quick protocol uses YCB objects (HSQ_YCB_DIR)"
)


def _benchmark(run_dir: Path, *extra: str) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-m", "hsqbench.cli", "benchmark", "--protocol", "quick"]
    cmd += ["--run", str(run_dir), "--jobs", "2", *extra]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as f:
        return list(csv.DictReader(f))


def test_quick_benchmark_runs_reports_and_resumes(tmp_path: Path) -> None:
    run_dir = tmp_path / "quick"
    first = _benchmark(run_dir)
    assert first.returncode == 0, first.stderr[-3000:]

    specs = build_trials(load_experiment_config("quick"))
    attempts = _rows(run_dir / "attempts.csv")
    rounds = _rows(run_dir / "rounds.csv")
    assert {r["trial_key"] for r in attempts} == {s.key for s in specs}
    assert all(r["status"] == "ok" for r in attempts), [r["detail"] for r in attempts]
    assert {r["outcome"] for r in attempts} <= {o.value for o in Outcome}
    assert len(rounds) == sum(s.experiment == "packed" for s in specs)
    for row in attempts:
        assert row["code_version"] and row["config_hash"]
        assert float(row["planning_s"]) > 0.0

    tables = (run_dir / "tables.md").read_text()
    assert "reported, real robot" in tables and "measured, simulation" in tables
    for png in ("gsr_per_object.png", "outcomes.png", "planning_time.png"):
        assert (run_dir / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"

    again = _benchmark(run_dir, "--resume")
    assert again.returncode == 0, again.stderr[-3000:]
    assert f"{len(specs)} already done" in again.stdout and "0 run" in again.stdout
    assert len(_rows(run_dir / "attempts.csv")) == len(attempts)
