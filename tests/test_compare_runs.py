"""bench/compare_runs.py: two runs' attempts compared trial by trial."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "bench" / "compare_runs.py"


@pytest.fixture(scope="module")
def compare_runs():
    spec = importlib.util.spec_from_file_location("compare_runs", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(folder: Path, rows: list[dict[str, str]]) -> Path:
    folder.mkdir()
    columns = ["trial_key", "attempt_index", "planner", "outcome", "target", "detail", "worker"]
    with (folder / "attempts.csv").open("w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows({c: r.get(c, "") for c in columns} for r in rows)
    return folder


def test_identical_runs_pass_and_changes_are_listed(compare_runs, tmp_path, capsys) -> None:
    base = [
        {
            "trial_key": "isolated/hsq/s0/mug/000",
            "attempt_index": "0",
            "planner": "hsq",
            "outcome": "success",
            "target": "mug",
            "worker": "a:1",
        },
        {
            "trial_key": "packed/hsq/s0/round/000",
            "attempt_index": "0",
            "planner": "hsq",
            "outcome": "dropped",
            "target": "bowl",
            "worker": "a:1",
        },
    ]
    a = _run(tmp_path / "a", base)
    same = _run(tmp_path / "same", [{**r, "worker": "b:2"} for r in base])  # volatile column
    assert compare_runs.main([str(a), str(same)]) == 0
    assert "identical: 2; changed: 0" in capsys.readouterr().out
    changed = [dict(base[0]), {**base[1], "outcome": "success", "detail": "in the bin"}]
    b = _run(tmp_path / "b", [*changed, {**base[1], "attempt_index": "1"}])
    assert compare_runs.main([str(a), str(b)]) == 1
    out = capsys.readouterr().out
    assert "identical: 1; changed: 1" in out
    assert "dropped -> success" in out and "only in B: 1" in out
    assert "packed/hsq/s0/round/000 attempt 0" in out and "'dropped' -> 'success'" in out
