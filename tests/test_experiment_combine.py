"""Rows of several runs of one protocol in one report (hsqbench.experiment.combine)."""

from __future__ import annotations

from dataclasses import replace

import pytest

from hsqbench.experiment.combine import RunMismatch
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.report import load_run, table1, write_report
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal"),
    isolated=IsolatedConfig(objects=("mug", "bowl"), attempts_per_object=3),
    packed=PackedConfig(objects=("mug", "bowl", "pear"), rounds=2, objects_per_round=2),
)


def test_a_later_planner_joins_the_main_runs_tables(tmp_path):
    main, later = tmp_path / "main", tmp_path / "later"
    run_benchmark(CONFIG, main, backend=FakeBackend(), planners=["hsq"], progress=False)
    run_benchmark(
        CONFIG,
        later,
        backend=FakeBackend(success={"antipodal": 0.0}),
        planners=["antipodal"],
        progress=False,
    )
    write_report(main, (later,))
    md = (main / "tables.md").read_text()
    assert "rows of antipodal come from run later" in md
    data = load_run(main)
    from hsqbench.experiment.combine import combine

    combine(data, load_run(later), later)
    t1 = table1(data).set_index("method")
    assert t1.loc["antipodal", "attempts"] == 6 and t1.loc["antipodal", "successes"] == 0
    assert t1.loc["hsq", "attempts"] == 6
    # Each row names the run it came from: the joined run's backend, not "this run".
    assert t1.loc["hsq", "source"] == "measured, fake backend (this run)"
    assert t1.loc["antipodal", "source"] == "measured, fake backend (run later)"
    antipodal_line = next(line for line in md.splitlines() if line.startswith("| antipodal |"))
    assert antipodal_line.endswith("| measured, fake backend (run later) |")
    assert "| 0/6 |" in antipodal_line  # joined rows keep their counts and intervals
    assert '- "measured, fake backend (run later)": the rows of antipodal' in md


def test_runs_of_other_poses_cannot_share_a_table(tmp_path):
    main, other = tmp_path / "main", tmp_path / "other"
    run_benchmark(CONFIG, main, backend=FakeBackend(), planners=["hsq"], progress=False)
    run_benchmark(
        replace(CONFIG, seeds=(1,)),
        other,
        backend=FakeBackend(),
        planners=["antipodal"],
        progress=False,
    )
    with pytest.raises(RunMismatch, match="'seeds' differs"):
        write_report(main, (other,))
