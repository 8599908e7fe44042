"""The report: tables and plots from the results files alone, reported beside measured rows."""

from __future__ import annotations

import csv
import warnings
from dataclasses import replace
from pathlib import Path

import pandas as pd
import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.report import (
    GSR_PLOT,
    HEADLINE_PLOT,
    OUTCOMES_PLOT,
    PAIRED_PLOT,
    TABLE1_CSV,
    TABLE2_CSV,
    TIMES_PLOT,
    load_run,
    write_report,
)
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.stats import wilson_interval
from tests.fake_backend import FakeBackend

CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal"),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=4),
    packed=PackedConfig(objects=("mug", "bowl", "hammer", "banana"), rounds=4, objects_per_round=3),
)
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("report") / "run"
    backend = FakeBackend(success={"antipodal": 0.4}, raise_on=("apple",))  # isolated only
    run_benchmark(CONFIG, path, backend=backend, progress=False)
    return path


def _counts_from_csv(run_dir: Path, experiment: str, planner: str) -> tuple[int, int, int]:
    """Successes, attempts and error trials counted straight from attempts.csv."""
    k = n = err = 0
    with open(run_dir / "attempts.csv") as f:
        for row in csv.DictReader(f):
            if row["experiment"] != experiment or row["planner"] != planner:
                continue
            if row["status"] == "error":
                err += 1
            else:
                n += 1
                k += row["success"] == "1"
    return k, n, err


def _cleared_from_csv(run_dir: Path, planner: str) -> tuple[int, int]:
    cleared = presented = 0
    with open(run_dir / "rounds.csv") as f:
        for row in csv.DictReader(f):
            if row["planner"] == planner and row["status"] == "ok":
                cleared += int(row["n_cleared"])
                presented += int(row["n_objects"])
    return cleared, presented


def test_report_from_the_csv_files_alone(run_dir: Path, tmp_path: Path) -> None:
    only_csv = tmp_path / "copy"
    only_csv.mkdir()
    for name in ("attempts.csv", "rounds.csv"):
        (only_csv / name).write_bytes((run_dir / name).read_bytes())
    with pytest.warns(UserWarning, match="infrastructure error"):
        written = write_report(only_csv)
    names = {p.name for p in written}
    assert {"tables.md", TABLE1_CSV, TABLE2_CSV, GSR_PLOT, OUTCOMES_PLOT, TIMES_PLOT} <= names
    md = (only_csv / "tables.md").read_text()
    assert "backend unknown" in md  # without run.json it does not claim a simulation


def test_tables_hold_reported_and_measured_rows_with_intervals(run_dir: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_report(run_dir)
    md = (run_dir / "tables.md").read_text()
    for reported in ("6-DOF GraspNet | 88.0", "GPD | 47.0", "PointNetGPD | 82.0",
                     "HSQ (paper) | 96.0", "GIGA | 83.3", "86.6", "HSQ (paper) | 81.3 | — | 81.3"):  # fmt: skip
        assert reported in md
    assert md.count("reported, real robot") >= 6 + 1  # six rows and the note
    assert "measured, fake backend (this run)" in md  # the backend is named, not "simulation"
    assert "Warning" in md and "infrastructure error" in md

    for planner in CONFIG.planners:
        k, n, err = _counts_from_csv(run_dir, "isolated", planner)
        low, high = wilson_interval(k, n)
        line = next(x for x in md.splitlines() if x.startswith(f"| {planner} |"))
        assert (
            f"| {100 * k / n:.1f} | [{100 * low:.1f}, {100 * high:.1f}] | {k}/{n} | 0 | {err} |"
            in line  # no planner errors (the fake backend has none), then the error trials
        )

        cleared, presented = _cleared_from_csv(run_dir, planner)
        kp, np_, errp = _counts_from_csv(run_dir, "packed", planner)
        packed_line = [x for x in md.splitlines() if x.startswith(f"| {planner} |")][1]
        # Packed intervals are over rounds: four rounds are too few for one.
        assert f"| {100 * cleared / presented:.1f} | — |" in packed_line
        assert f"| {100 * kp / np_:.1f} |" in packed_line
        assert f"| {errp} | measured" in packed_line

    with open(run_dir / TABLE1_CSV) as f:
        rows = list(csv.DictReader(f))
    measured = [r for r in rows if r["source"].startswith("measured")]
    assert [r["method"] for r in measured] == list(CONFIG.planners)
    assert all(float(r["ci_low_percent"]) <= float(r["gsr_percent"]) <= float(r["ci_high_percent"])
               for r in measured)  # fmt: skip
    with open(run_dir / TABLE2_CSV) as f:
        t2 = {r["method"]: r for r in csv.DictReader(f)}
    assert (
        t2["GIGA"]["source"] == "reported, real robot" and float(t2["GIGA"]["cr_percent"]) == 86.6
    )


def test_a_run_on_other_objects_shows_no_reported_rows(tmp_path: Path) -> None:
    """The paper's rows describe its 15 objects: packed rounds that draw another object, and
    the headline plot of such a run, leave them out and say why."""
    from hsqbench.experiment.plots.headline import reported_points
    from hsqbench.experiment.run_data import load_run

    config = replace(CONFIG, packed=replace(CONFIG.packed, objects=("mug", "bowl", "pear")))
    run_benchmark(config, tmp_path / "other", backend=FakeBackend(), progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_report(tmp_path / "other")
    with open(tmp_path / "other" / TABLE2_CSV) as f:
        assert all(r["source"].startswith("measured") for r in csv.DictReader(f))
    with open(tmp_path / "other" / TABLE1_CSV) as f:  # isolated objects are the paper's
        assert "HSQ (paper)" in {r["method"] for r in csv.DictReader(f)}
    points = reported_points(load_run(tmp_path / "other").meta)
    assert set(points["experiment"]) == {"isolated", "pile"}  # pile: GIGA's own objects
    assert "real robot" in (tmp_path / "other" / "tables.md").read_text()
    isolated_only = replace(config, isolated=replace(CONFIG.isolated, objects=("pear",)))
    run_benchmark(isolated_only, tmp_path / "none", backend=FakeBackend(), progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_report(tmp_path / "none")
    md = (tmp_path / "none" / "tables.md").read_text()
    assert "real robot" not in md and "reported rows are left out" in md


def test_plots_are_valid_pngs(run_dir: Path) -> None:
    from matplotlib.image import imread

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_report(run_dir)
    for name in (HEADLINE_PLOT, OUTCOMES_PLOT, PAIRED_PLOT, GSR_PLOT, TIMES_PLOT):
        path = run_dir / name
        assert path.read_bytes()[:8] == PNG_MAGIC
        image = imread(path)
        assert image.ndim == 3 and image.shape[0] > 200 and image.shape[1] > 200
        assert image.std() > 0.01  # not a blank canvas


def test_report_command(run_dir: Path, capsys) -> None:
    from hsqbench.cli import main

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert main(["report", "--run", str(run_dir)]) == 0
    assert "tables.md" in capsys.readouterr().out
    assert main(["report", "--run", str(run_dir / "nope")]) == 2
    assert "not a folder" in capsys.readouterr().err


def _three_rounds_of_three() -> ExperimentConfig:
    """hsq alone, packed only: three rounds of the same three objects."""
    return ExperimentConfig(
        planners=("hsq",),
        isolated=IsolatedConfig(enabled=False),
        packed=PackedConfig(objects=("mug", "bowl", "pear"), rounds=3, objects_per_round=3),
    )


class _EarlyStop(FakeBackend):
    """Ends every packed round after its first attempt, breaking the paper's stop rule."""

    def run_packed(self, objects, seed, planner):
        result = super().run_packed(objects, seed, planner)
        result.attempts = result.attempts[:1]
        result.objects_cleared = result.objects_cleared[:1] if result.attempts[0].success else []
        return result


def test_report_flags_rounds_that_break_the_stop_rule(tmp_path: Path) -> None:
    config = _three_rounds_of_three()
    run_benchmark(config, tmp_path / "early", backend=_EarlyStop(), progress=False)
    write_report(tmp_path / "early")
    assert "check the trial runner's stop rule" in (tmp_path / "early" / "tables.md").read_text()
    run_benchmark(config, tmp_path / "fine", backend=FakeBackend(), progress=False)
    write_report(tmp_path / "fine")
    assert "stop rule" not in (tmp_path / "fine" / "tables.md").read_text()


class _LostRest(_EarlyStop):
    """Ends each round after its first attempt with the objects not cleared taken out as lost
    (out of the workspace), as the trial runner does: the table is then empty."""

    def run_packed(self, objects, seed, planner):
        result = super().run_packed(objects, seed, planner)
        result.objects_lost = [o for o in result.objects if o not in result.objects_cleared]
        return result


def test_report_counts_objects_lost_out_of_the_workspace_as_off_the_table(tmp_path: Path) -> None:
    config = _three_rounds_of_three()
    run_benchmark(config, tmp_path / "lost", backend=_LostRest(), progress=False)
    write_report(tmp_path / "lost")
    assert "stop rule" not in (tmp_path / "lost" / "tables.md").read_text()
    rounds = load_run(tmp_path / "lost").rounds
    assert (rounds["n_cleared"] + rounds["n_lost"] == 3).all() and (rounds["n_lost"] > 0).any()


def test_report_reads_the_runs_own_stop_rule_and_accepts_the_attempt_cap(tmp_path: Path) -> None:
    """A round that the attempt cap ends, objects left and no two failures in a row, follows
    the rule: the report checks it against the run's stop rule (stored in run.json), so it is
    not flagged."""
    from hsqbench.sim.stop_rule import PackedConfig as StopRule

    config = _three_rounds_of_three()
    capped = FakeBackend(default_success=0.3, stop_rule=StopRule(5, max_attempts=2))
    run_benchmark(config, tmp_path / "capped", backend=capped, progress=False)
    write_report(tmp_path / "capped")
    assert "stop rule" not in (tmp_path / "capped" / "tables.md").read_text()
    rounds = pd.read_csv(tmp_path / "capped" / "rounds.csv")
    assert (rounds["n_attempts"] == 2).all() and (rounds["n_cleared"] < 3).all()  # at the cap
