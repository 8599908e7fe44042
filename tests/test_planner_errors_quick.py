"""A planner that crashes scores as one that fails: on the quick protocol, in the real simulator,
a plugin whose ``stages`` always raises, and one that returns a NaN grasp, get 0 % GSR and CR
over all their attempts (``planner_error``, each naming the plugin's file and line), and
``hsqbench trial`` with such a plugin prints one line and exits 2.

The trials are the quick protocol's; the surface sensor and no graspability check keep them
fast (the planner is called on a cloud all the same)."""

from __future__ import annotations

import csv
import os
from pathlib import Path

import pytest

from hsqbench.cli import main
from hsqbench.experiment.backend import SimBackend
from hsqbench.experiment.config import load_experiment_config
from hsqbench.experiment.markdown import ERROR_HEADS
from hsqbench.experiment.report import outcome_table, table1, table2
from hsqbench.experiment.run_data import load_run
from hsqbench.experiment.runner import run_benchmark
from hsqbench.planner import registry
from hsqbench.runs import protocol_planners
from tests.test_planner_failure import BROKEN, line_of

pytestmark = pytest.mark.skipif(
    not os.environ.get("HSQ_YCB_DIR"), reason="the quick protocol uses YCB objects (HSQ_YCB_DIR)"
)
FAST = (("sensor", "surface"), ("graspability", None))


@pytest.fixture(scope="module")
def plugin(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("plugin") / "broken.py"
    path.write_text(BROKEN)
    return path


@pytest.fixture(scope="module")
def quick_run(plugin, tmp_path_factory):
    """The quick protocol with the raising and the NaN planners (in this process)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(registry, "_SPECS", {})
        mp.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))
        names = [registry.resolve_planner(f"{plugin}:{c}") for c in ("Raises", "NanPose")]
        config, planners = protocol_planners(load_experiment_config("quick"), names)
        run_dir = tmp_path_factory.mktemp("runs") / "broken"
        backend = SimBackend(config.trial_config, overrides=FAST)
        summary = run_benchmark(config, run_dir, backend=backend, planners=names, progress=False)
    assert set(names) <= set(planners)
    with (run_dir / "attempts.csv").open(newline="") as f:
        rows = list(csv.DictReader(f))
    return load_run(run_dir), rows, summary


@pytest.mark.parametrize("planner", ["raises", "nan-pose"])
def test_a_broken_planner_scores_zero_over_all_its_attempts(quick_run, planner):
    data, rows, _ = quick_run
    mine = [r for r in rows if r["planner"] == planner]
    assert mine and all(r["status"] == "ok" for r in mine), [r["detail"] for r in mine]
    assert {r["outcome"] for r in mine} == {"planner_error"}
    # The packed round went on after the first failed attempt and ended at the second (the
    # stop rule's two consecutive failures), as it does after "no grasp found".
    assert [r["attempt_index"] for r in mine if r["experiment"] == "packed"] == ["0", "1"]
    for experiment, table in (("isolated", table1(data)), ("packed", table2(data))):
        n = sum(r["experiment"] == experiment for r in mine)
        row = table[table["method"] == planner].iloc[0]
        assert n > 0 and (row["successes"], row["attempts"]) == (0, n)
        assert row["planner_errors"] == n and row["errors"] == 0
        assert row["gsr_percent"] == 0.0
    packed = table2(data)
    row = packed[packed["method"] == planner].iloc[0]
    assert row["cr_percent"] == 0.0 and row["objects_presented"] == 2
    counts = outcome_table(data)
    assert counts[counts["planner"] == planner]["planner_error"].sum() == len(mine)


def test_a_nan_grasp_names_the_plugins_line_not_the_grasp_checks(quick_run, plugin):
    _, rows, _ = quick_run
    for r in (r for r in rows if r["planner"] == "nan-pose"):
        assert line_of(plugin, "nan-pose") in r["detail"] and "grasp.py" not in r["detail"]
        assert "grasp position and rotation must be finite" in r["detail"]
    for r in (r for r in rows if r["planner"] == "raises"):
        assert line_of(plugin, "raises") in r["detail"] and "RuntimeError" in r["detail"]


def test_the_report_counts_planner_errors_apart_from_infrastructure_errors(quick_run):
    from hsqbench.experiment.markdown import render_markdown
    from hsqbench.experiment.report import table1_per_object, time_table

    data, _, _ = quick_run
    t1, t2 = table1(data), table2(data)
    md = render_markdown(
        data, t1, table1_per_object(data), t2, outcome_table(data), time_table(data)
    )
    assert " | ".join(ERROR_HEADS) in md
    line = next(x for x in md.splitlines() if x.startswith("| raises |"))
    assert line.endswith("| 0/2 | 2 | 0 | measured, simulation (this run) |"), line


def test_a_sweep_point_counts_planner_errors_as_failures(quick_run):
    from hsqbench.experiment.sweep_table import run_rows

    data, rows, _ = quick_run
    points = run_rows(data, ["isolated", "packed"])
    assert {(r["planner"], r["experiment"]) for r in points} == {
        (p, e) for p in ("raises", "nan-pose") for e in ("isolated", "packed")
    }
    for row in points:
        n = sum(
            r["planner"] == row["planner"] and r["experiment"] == row["experiment"] for r in rows
        )
        assert (row["n"], row["successes"], row["planner_errors"], row["errors"]) == (n, 0, n, 0)


def test_the_runs_summary_counts_planner_errors_apart_from_infrastructure_errors(quick_run, plugin):
    _, rows, summary = quick_run
    assert summary.errors == 0 and summary.planner_errors == len(rows) > 0
    assert line_of(plugin, "raises") in summary.first_planner_error


def test_a_benchmark_refuses_a_plugin_that_cannot_be_built_before_any_trial(plugin, monkeypatch):
    monkeypatch.setattr(registry, "_SPECS", {})
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))
    name = registry.resolve_planner(f"{plugin}:BadInit")
    with pytest.raises(ValueError, match=f"cannot be built: OSError at {line_of(plugin, name)}"):
        SimBackend().check((name,))


@pytest.mark.parametrize(("cls", "name"), [("Raises", "raises"), ("Listed", "listed")])
def test_trial_prints_one_line_and_exits_2(plugin, capsys, monkeypatch, cls, name):
    monkeypatch.setattr(registry, "_SPECS", {})
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))
    argv = ["trial", "--planner", f"{plugin}:{cls}", "--object", "foam_brick"]
    code = main([*argv, "--sensor", "surface"])
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ""
    assert captured.err.count("\n") == 1 and "Traceback" not in captured.err
    assert captured.err.startswith(f"hsqbench trial: error: planner {name!r}")
    assert line_of(plugin, name) in captured.err
