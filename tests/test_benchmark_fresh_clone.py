"""A fresh clone with no YCB folder: `make benchmark`'s command downloads the objects its
protocol uses, builds them and runs to its tables, here against a local archive server.

The quick protocol (two YCB objects) runs through the real simulator on synthetic stand-ins for
the two scans, served in the official layout from 127.0.0.1; nothing contacts the internet.
"""

from __future__ import annotations

import csv
import os
import subprocess
import sys
from pathlib import Path

from hsqbench.experiment.config import load_experiment_config
from tests.ycb_server import archives, serve


def _benchmark(run_dir: Path, env: dict[str, str]) -> subprocess.CompletedProcess:
    # The command of `make benchmark CONFIG=quick`.
    cmd = [sys.executable, "-m", "hsqbench.cli", "benchmark", "--protocol", "quick"]
    cmd += ["--run", str(run_dir), "--jobs", "2", "--resume"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=900, env=env, check=False)


def test_benchmark_downloads_builds_and_runs_without_a_ycb_folder(tmp_path: Path) -> None:
    objects = load_experiment_config("quick").object_names()
    env = {k: v for k, v in os.environ.items() if k not in ("HSQ_YCB_DIR", "HSQ_YCB_URL")}
    env.update(HSQ_DATA_DIR=str(tmp_path / "data"), HSQ_CACHE_DIR=str(tmp_path / "cache"))
    with serve() as server:
        server.files.update(archives(*objects))
        env["HSQ_YCB_URL"] = server.base_url
        run_dir = tmp_path / "run"
        first = _benchmark(run_dir, env)
        assert first.returncode == 0, first.stderr[-4000:]
        assert sorted(n for n, _ in server.requests) == sorted(server.files)  # each once
        again = _benchmark(run_dir, env)
        assert again.returncode == 0, again.stderr[-4000:]
        assert len(server.requests) == len(server.files)  # nothing fetched the second time

    assert f"downloading {len(objects)} YCB object(s)" in first.stderr
    assert "shared" not in first.stderr + first.stdout  # no path of this project's machines
    data = tmp_path / "data" / "ycb"
    with (data / "objects.csv").open() as f:
        assert {r["name"] for r in csv.DictReader(f)} == set(objects)
    with (run_dir / "attempts.csv").open() as f:
        attempts = list(csv.DictReader(f))
    assert attempts and all(r["status"] == "ok" for r in attempts), [r["detail"] for r in attempts]
    assert {o for r in attempts for o in r["objects"].split(";")} == set(objects)
    assert "measured, simulation" in (run_dir / "tables.md").read_text()
    assert "already done" in again.stdout and "0 run" in again.stdout
