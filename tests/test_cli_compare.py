"""``hsqbench compare``: two runs of one protocol, paired trial by trial."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from hsqbench.cli import main
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

RESULTS = Path(__file__).resolve().parents[1] / "results"
TURN, REDRAW = RESULTS / "ycb3-turn", RESULTS / "ycb3-redraw"  # hsq at two code versions


def test_two_committed_runs_print_their_transitions(capsys) -> None:
    assert main(["compare", str(TURN), str(REDRAW), "--fail-if-worse", "--show", "3"]) == 0
    out = capsys.readouterr().out
    assert "paired difference B - A" in out
    iso = next(x for x in out.splitlines() if x.strip().startswith("isolated GSR  hsq"))
    assert iso.rstrip().endswith("better")  # the later version's new draw of stage one
    assert "no_grasp_found -> success" in out and "<- changed" in out
    assert "changed attempts (first 3 of" in out
    assert main(["compare", str(TURN), str(REDRAW), "--fail-if-changed"]) == 1


def _make_worse(src: Path, dst: Path, planner: str, flips: int) -> int:
    """A copy of ``src`` where ``planner`` fails ``flips`` isolated attempts it succeeded in."""
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.png", "table*", "*.md"))
    with open(dst / "attempts.csv", newline="") as f:
        reader = csv.DictReader(f)
        columns, rows = reader.fieldnames, list(reader)
    done = 0
    for r in rows:
        mine = r["experiment"] == "isolated" and r["planner"] == planner
        if done < flips and mine and r["success"] == "1":
            r.update(success="0", outcome="dropped")
            done += 1
    with open(dst / "attempts.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    return done


def test_fail_if_worse_exits_non_zero_only_when_b_is_significantly_worse(tmp_path, capsys) -> None:
    worse = tmp_path / "worse"
    assert _make_worse(REDRAW, worse, "hsq", 12) == 12  # 12 of 1,170 pairs lost, none won
    assert main(["compare", str(REDRAW), str(worse)]) == 0  # reports, does not judge
    assert main(["compare", str(REDRAW), str(worse), "--fail-if-worse"]) == 1
    out = capsys.readouterr().out
    assert "FAIL: B is significantly worse than A for hsq (isolated GSR)" in out
    assert "success -> dropped" in out
    # The other way round B is better: no failure.
    assert main(["compare", str(worse), str(REDRAW), "--fail-if-worse"]) == 0
    few = tmp_path / "few"
    _make_worse(REDRAW, few, "hsq", 3)  # 0:3 discordant pairs, p = 0.25: not significant
    assert main(["compare", str(REDRAW), str(few), "--fail-if-worse"]) == 0


CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal"),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=4),
    packed=PackedConfig(objects=("mug", "bowl", "pear", "banana"), rounds=3, objects_per_round=3),
)


def test_identical_runs_pass_fail_if_changed_and_changed_ones_list_their_attempts(
    tmp_path, capsys
) -> None:
    a, same, other = tmp_path / "a", tmp_path / "same", tmp_path / "other"
    run_benchmark(CONFIG, a, backend=FakeBackend(), progress=False)
    run_benchmark(CONFIG, same, backend=FakeBackend(), progress=False)  # timings differ
    assert main(["compare", str(a), str(same), "--fail-if-changed"]) == 0
    out = capsys.readouterr().out
    assert "changed: 0" in out and "only in A: 0; only in B: 0" in out
    assert "packed CR" in out  # rounds pair up too
    run_benchmark(CONFIG, other, backend=FakeBackend(success={"hsq": 0.2}), progress=False)
    assert main(["compare", str(a), str(other), "--fail-if-changed", "--planners", "hsq"]) == 1
    out = capsys.readouterr().out
    assert "antipodal" not in out.split("outcome transitions")[0]
    assert "success -> " in out and "changed attempts (first" in out


def test_bad_input_is_one_line(tmp_path, capsys) -> None:
    assert main(["compare", str(tmp_path / "nope"), str(REDRAW)]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert main(["compare", str(REDRAW), str(REDRAW), "--columns", "outcome,wrong"]) == 2
    assert "--columns wrong" in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--fail-if-worse", "--fail-if-changed"])
def test_a_run_against_itself_passes(flag, capsys) -> None:
    assert main(["compare", str(REDRAW), str(REDRAW), flag]) == 0
    assert "changed: 0" in capsys.readouterr().out
