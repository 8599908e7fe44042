"""``hsqbench compare``: two runs of one protocol, paired trial by trial."""

from __future__ import annotations

import csv
import io
import shutil
from pathlib import Path

import pytest

from hsqbench.cli import main
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.rows import read_packed
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

CANON = Path(__file__).resolve().parents[1] / "results" / "ycb3"  # canonical; attempts gzipped


def _read(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """A run's CSV, plain or packed (a ``.gz`` path, whole or in pieces)."""
    data = read_packed(path) if path.suffix == ".gz" else path.read_bytes()
    reader = csv.DictReader(io.StringIO(data.decode()))
    return list(reader.fieldnames or []), list(reader)


def _write(path: Path, columns: list[str], rows: list[dict[str, str]]) -> None:
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)


@pytest.fixture(scope="module")
def hsq_run(tmp_path_factory) -> Path:
    """``results/ycb3`` cut to hsq's rows (an eighth of them), its files written plain."""
    dst = tmp_path_factory.mktemp("canon") / "ycb3"
    shutil.copytree(CANON, dst, ignore=shutil.ignore_patterns("*.png", "*.csv", "*.md", "*.gz*"))
    for name, src in (
        ("attempts.csv", CANON / "attempts.csv.gz"),
        ("rounds.csv", CANON / "rounds.csv"),
    ):
        columns, rows = _read(src)
        _write(dst / name, columns, [r for r in rows if r["planner"] == "hsq"])
    return dst


def _copy_flipping(src: Path, dst: Path, planner: str, flips: int, old: str, new: str) -> int:
    """A copy of ``src`` where ``planner``'s first ``flips`` isolated attempts that ended
    ``old`` end ``new`` instead; returns how many changed."""
    shutil.copytree(src, dst)
    columns, rows = _read(src / "attempts.csv")
    done = 0
    for r in rows:
        mine = r["experiment"] == "isolated" and r["planner"] == planner
        if done < flips and mine and r["outcome"] == old:
            r.update(success=str(int(new == "success")), outcome=new)
            done += 1
    _write(dst / "attempts.csv", columns, rows)
    return done


def test_a_changed_copy_of_a_committed_run_prints_its_transitions(
    hsq_run, tmp_path, capsys
) -> None:
    better = tmp_path / "better"
    assert _copy_flipping(hsq_run, better, "hsq", 20, "no_grasp_found", "success") == 20
    assert main(["compare", str(hsq_run), str(better), "--fail-if-worse", "--limit", "3"]) == 0
    out = capsys.readouterr().out
    assert "paired difference B - A" in out
    iso = next(x for x in out.splitlines() if x.strip().startswith("isolated GSR  hsq"))
    assert iso.rstrip().endswith("better")  # 20 pairs won, none lost
    assert "no_grasp_found -> success" in out and "<- changed" in out
    assert "changed attempts (first 3 of 20" in out
    assert main(["compare", str(hsq_run), str(better), "--fail-if-changed"]) == 1
    assert main(["compare", str(hsq_run), str(hsq_run), "--fail-if-changed"]) == 0


def test_fail_if_worse_exits_non_zero_only_when_b_is_significantly_worse(
    hsq_run, tmp_path, capsys
) -> None:
    worse = tmp_path / "worse"
    assert _copy_flipping(hsq_run, worse, "hsq", 12, "success", "dropped") == 12  # 0:12 pairs
    assert main(["compare", str(hsq_run), str(worse)]) == 0  # reports, does not judge
    assert main(["compare", str(hsq_run), str(worse), "--fail-if-worse"]) == 1
    out = capsys.readouterr().out
    assert "FAIL: B is significantly worse than A for hsq (isolated GSR)" in out
    assert "success -> dropped" in out
    # The other way round B is better: no failure.
    assert main(["compare", str(worse), str(hsq_run), "--fail-if-worse"]) == 0
    few = tmp_path / "few"
    _copy_flipping(hsq_run, few, "hsq", 3, "success", "dropped")  # 0:3 pairs, p = 0.25
    assert main(["compare", str(hsq_run), str(few), "--fail-if-worse"]) == 0


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


def test_timings_are_not_changes(hsq_run, tmp_path, capsys) -> None:
    """Every timing column of an attempt, the planner's stage times and the IK's included, may
    differ between two runs of the same trials; none of them makes an attempt "changed"."""
    b = tmp_path / "b"
    shutil.copytree(hsq_run, b)
    columns, rows = _read(b / "attempts.csv")
    for r in rows:
        for c in ("perception_s", "planning_s", "execution_s", "motion_planning_s", "trial_wall_s"):
            r[c] = str(float(r[c] or 0.0) + 0.5)
        r["planner_stages_s"] = '{"total": 9.0}'
    _write(b / "attempts.csv", columns, rows)
    assert main(["compare", str(hsq_run), str(b), "--fail-if-changed"]) == 0
    assert "changed: 0" in capsys.readouterr().out


def test_part_of_a_run_is_checked_against_those_trials_only(hsq_run, tmp_path, capsys) -> None:
    """A smaller protocol on the same seeds (a few trials of a committed run, run again to
    check today's code) passes --fail-if-changed with --part, and fails without it."""
    part = tmp_path / "part"
    shutil.copytree(hsq_run, part)
    columns, rows = _read(part / "attempts.csv")
    keys = sorted({r["trial_key"] for r in rows if r["experiment"] == "isolated"})[:40]
    _write(part / "attempts.csv", columns, [r for r in rows if r["trial_key"] in keys])
    round_columns, _ = _read(part / "rounds.csv")
    _write(part / "rounds.csv", round_columns, [])
    assert main(["compare", str(hsq_run), str(part), "--fail-if-changed"]) == 1
    capsys.readouterr()
    assert main(["compare", str(hsq_run), str(part), "--part", "--fail-if-changed"]) == 0
    out = capsys.readouterr().out
    assert "identical: 40; changed: 0" in out and "only in A: 0; only in B: 0" in out
    _copy_flipping(part, tmp_path / "flipped", "hsq", 3, "success", "dropped")
    assert (
        main(["compare", str(hsq_run), str(tmp_path / "flipped"), "--part", "--fail-if-changed"])
        == 1
    )


def test_bad_input_is_one_line(hsq_run, tmp_path, capsys) -> None:
    assert main(["compare", str(tmp_path / "nope"), str(hsq_run)]) == 2
    assert "is not a folder" in capsys.readouterr().err
    assert main(["compare", str(hsq_run), str(hsq_run), "--columns", "outcome,wrong"]) == 2
    assert "--columns wrong" in capsys.readouterr().err


@pytest.mark.parametrize("flag", ["--fail-if-worse", "--fail-if-changed"])
def test_a_run_against_itself_passes(hsq_run, flag, capsys) -> None:
    assert main(["compare", str(hsq_run), str(hsq_run), flag]) == 0
    assert "changed: 0" in capsys.readouterr().out


def test_runs_of_other_protocols_are_refused_in_one_line(hsq_run, tmp_path, capsys) -> None:
    """Another protocol's run.json (results/paper3's: other trial config, objects, draws):
    nothing in it pairs with ycb3's trials, so compare refuses instead of passing."""
    other = tmp_path / "paper3like"
    shutil.copytree(hsq_run, other)
    shutil.copy(CANON.parent / "paper3" / "run.json", other / "run.json")
    assert main(["compare", str(hsq_run), str(other), "--fail-if-worse"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "differs from" in err[0] and "same protocol" in err[0]


def test_runs_with_nothing_in_common_are_refused(hsq_run, tmp_path, capsys) -> None:
    renamed = tmp_path / "renamed"
    shutil.copytree(hsq_run, renamed)
    for name in ("attempts.csv", "rounds.csv"):
        columns, rows = _read(renamed / name)
        for r in rows:
            r["planner"] = "antipodal"
            r["trial_key"] = r["trial_key"].replace("/hsq/", "/antipodal/")
        _write(renamed / name, columns, rows)
    assert main(["compare", str(hsq_run), str(renamed), "--fail-if-worse"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no attempt or round pairs up" in err[0]


def test_part_with_seeds_the_full_run_lacks_is_refused(hsq_run, tmp_path, capsys) -> None:
    import json

    part = tmp_path / "part"
    shutil.copytree(hsq_run, part)
    meta = json.loads((part / "run.json").read_text())
    meta["config"]["seeds"] = [7]
    (part / "run.json").write_text(json.dumps(meta))
    assert main(["compare", str(hsq_run), str(part), "--part"]) == 2
    assert "base seeds [7] are not among" in capsys.readouterr().err


def test_part_with_another_draw_for_a_round_it_ran_is_refused(hsq_run, tmp_path, capsys) -> None:
    import json

    part = tmp_path / "part"
    shutil.copytree(hsq_run, part)
    meta = json.loads((part / "run.json").read_text())
    first = sorted(meta["packed_draws"])[0]
    meta["packed_draws"][first]["objects"] = ["dice", "fork", "knife", "plate", "spoon"]
    (part / "run.json").write_text(json.dumps(meta))
    assert main(["compare", str(hsq_run), str(part), "--part"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"round {first} drew other objects" in err[0]


def test_fail_if_worse_judges_by_holm_adjusted_p(hsq_run, tmp_path, capsys) -> None:
    """Packed CR is tested over rounds: a few objects lost in a few rounds is not a regression."""
    b = tmp_path / "b"
    shutil.copytree(hsq_run, b)
    columns, rows = _read(b / "rounds.csv")
    changed = 0
    for r in rows:
        if changed < 3 and r["trial_key"].startswith("packed/") and r["objects_cleared"]:
            kept = r["objects_cleared"].split(";")[1:]
            r["objects_cleared"], r["n_cleared"] = ";".join(kept), str(len(kept))
            changed += 1
    _write(b / "rounds.csv", columns, rows)
    assert main(["compare", str(hsq_run), str(b), "--fail-if-worse"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "packed CR" in x and "hsq" in x)
    assert "45 rounds" in line and line.rstrip().endswith("not distinguishable")


@pytest.mark.slow
def test_the_canonical_paper3_and_ycb3_are_not_compared(capsys) -> None:
    assert main(["compare", str(CANON.parent / "paper3"), str(CANON), "--fail-if-worse"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_single_round_prints_no_nan_interval(tmp_path, capsys) -> None:
    """A quick run has one packed round: its CR difference has no interval, shown as a dash."""
    from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
    from hsqbench.experiment.runner import run_benchmark

    config = ExperimentConfig(
        planners=("a",),
        isolated=IsolatedConfig(objects=("mug", "bowl")),
        packed=PackedConfig(objects=("mug", "bowl"), rounds=1, objects_per_round=2),
    )
    for name in ("a", "b"):
        run_benchmark(config, tmp_path / name, backend=FakeBackend(), progress=False)
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    assert "packed CR" in out and "nan" not in out and "[—]" in out
