"""The runner: a run, a killed run resumed, refusal to mix configs, errors kept apart."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.results import ResultsError, load_results
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.seeds import build_trials
from tests.fake_backend import FakeBackend

SMALL = ExperimentConfig(
    planners=("a", "b"),
    seeds=(0,),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=2),
    packed=PackedConfig(objects=("mug", "bowl", "apple"), rounds=2, objects_per_round=2),
)
N_SMALL = 2 * (3 * 2 + 2)


def _keys(run_dir: Path) -> list[str]:
    """Trial keys of the complete trials, with repetition (a double count would show)."""
    results = load_results(run_dir)
    keys = [r["trial_key"] for r in results.attempts if r["attempt_index"] in ("0", "-1")]
    return sorted(keys)


def _raw_key_counts(run_dir: Path) -> dict[str, int]:
    counts: dict[str, int] = {}
    for line in (run_dir / "attempts.csv").read_text().splitlines()[1:]:
        key, _, rest = line.partition(",")
        first = rest.split(",")[6]  # attempt_index
        if first in ("0", "-1"):
            counts[key] = counts.get(key, 0) + 1
    return counts


def test_a_run_records_every_trial_once(tmp_path) -> None:
    summary = run_benchmark(SMALL, tmp_path / "r", backend=FakeBackend(), progress=False)
    assert (summary.selected, summary.ran, summary.skipped, summary.errors) == (N_SMALL,) * 2 + (
        0,
        0,
    )
    assert _keys(tmp_path / "r") == sorted(s.key for s in build_trials(SMALL))
    import json

    meta = json.loads((tmp_path / "r" / "run.json").read_text())
    assert meta["config_hash"] == summary.config_hash
    assert meta["config"]["planners"] == ["a", "b"]
    assert meta["sessions"][0]["status"] == "finished"
    assert meta["backend"]["backend"] == "fake" and meta["machine"]["host"]


def test_interrupted_run_resumes_without_loss_or_double_count(tmp_path) -> None:
    run_dir = tmp_path / "r"
    with pytest.raises(KeyboardInterrupt):
        run_benchmark(SMALL, run_dir, backend=FakeBackend(interrupt_after=5), progress=False)
    first = load_results(run_dir)
    assert len(first.complete_keys) == 5
    kept_rows = {tuple(r.items()) for r in first.attempts}

    summary = run_benchmark(SMALL, run_dir, backend=FakeBackend(), resume=True, progress=False)
    assert (summary.skipped, summary.ran) == (5, N_SMALL - 5)
    final = load_results(run_dir)
    assert kept_rows <= {tuple(r.items()) for r in final.attempts}  # nothing completed was lost
    assert _keys(run_dir) == sorted(s.key for s in build_trials(SMALL))
    assert set(_raw_key_counts(run_dir).values()) == {1}
    # Same rows as an uninterrupted run, apart from timing and provenance columns.
    ref = tmp_path / "ref"
    run_benchmark(SMALL, ref, backend=FakeBackend(), progress=False)
    assert _comparable(ref) == _comparable(run_dir)
    import json

    sessions = json.loads((run_dir / "run.json").read_text())["sessions"]
    assert [s["status"] for s in sessions] == ["interrupted", "finished"]


def _comparable(run_dir: Path) -> list[tuple]:
    from hsqbench.experiment.results import VOLATILE_COLUMNS

    rows = load_results(run_dir).attempts
    return sorted(tuple(v for k, v in r.items() if k not in VOLATILE_COLUMNS) for r in rows)


def test_killed_process_resumes_and_drops_a_partial_line(tmp_path) -> None:
    run_dir = tmp_path / "killed"
    script = textwrap.dedent(
        f"""
        from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
        from tests.fake_backend import FakeBackend
        from hsqbench.experiment.runner import run_benchmark
        config = ExperimentConfig(
            planners=("a", "b"),
            isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=2),
            packed=PackedConfig(objects=("mug", "bowl", "apple"), rounds=2, objects_per_round=2),
        )
        run_benchmark(config, {str(run_dir)!r}, backend=FakeBackend(sleep_s=0.1), progress=False)
        """
    )
    proc = subprocess.Popen([sys.executable, "-c", script])
    attempts = run_dir / "attempts.csv"
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if attempts.exists() and attempts.read_text().count("\n") >= 5:
            break
        time.sleep(0.02)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    before = load_results(run_dir)
    assert 4 <= len(before.complete_keys) < N_SMALL
    # Simulate the kill landing mid-write as well.
    with open(attempts, "a") as f:
        f.write("isolated/a/s0/apple/001,isolated,a,0,1,")

    summary = run_benchmark(SMALL, run_dir, backend=FakeBackend(), resume=True, progress=False)
    assert summary.skipped == len(before.complete_keys)
    assert attempts.read_text().endswith("\n")
    assert _keys(run_dir) == sorted(s.key for s in build_trials(SMALL))
    assert set(_raw_key_counts(run_dir).values()) == {1}


def test_resume_refuses_another_config_and_force_moves_it_aside(tmp_path) -> None:
    run_dir = tmp_path / "r"
    run_benchmark(SMALL, run_dir, backend=FakeBackend(), progress=False)
    other = ExperimentConfig(
        planners=SMALL.planners,
        isolated=SMALL.isolated,
        packed=PackedConfig(objects=("mug", "bowl", "apple"), rounds=3, objects_per_round=2),
    )
    with pytest.raises(ResultsError, match="new --run name"):
        run_benchmark(other, run_dir, backend=FakeBackend(), resume=True, progress=False)
    # The backend's settings are part of the hash too.
    with pytest.raises(ResultsError, match="config hash"):
        run_benchmark(
            SMALL, run_dir, backend=FakeBackend(default_success=0.3), resume=True, progress=False
        )
    with pytest.raises(ResultsError, match="--resume"):
        run_benchmark(SMALL, run_dir, backend=FakeBackend(), progress=False)
    summary = run_benchmark(other, run_dir, backend=FakeBackend(), force=True, progress=False)
    assert summary.skipped == 0 and summary.ran == len(build_trials(other))
    moved = [p for p in tmp_path.iterdir() if p.name.startswith("r.replaced-")]
    assert len(moved) == 1 and len(load_results(moved[0]).complete_keys) == N_SMALL


def test_a_refused_resume_names_what_differs(tmp_path) -> None:
    """Not only two hashes: the settings that differ, with their old and new values."""
    run_dir = tmp_path / "r"
    run_benchmark(SMALL, run_dir, backend=FakeBackend(), progress=False)
    more = ExperimentConfig(
        planners=(*SMALL.planners, "c"), isolated=SMALL.isolated, packed=SMALL.packed
    )
    with pytest.raises(ResultsError) as refused:
        run_benchmark(more, run_dir, backend=FakeBackend(default_success=0.3), resume=True)
    message = str(refused.value)
    planners = ", ".join(f'"{p}"' for p in SMALL.planners)
    assert f'config.planners: [{planners}] -> [{planners}, "c"]' in message
    assert "backend.default_success: 0.8 -> 0.3" in message


def test_selection_then_resume_completes_the_same_run(tmp_path) -> None:
    run_dir = tmp_path / "r"
    s1 = run_benchmark(
        SMALL, run_dir, backend=FakeBackend(), planners=["a"], experiments=["packed"],
        progress=False,
    )  # fmt: skip
    assert s1.ran == 2
    s2 = run_benchmark(SMALL, run_dir, backend=FakeBackend(), resume=True, progress=False)
    assert (s2.skipped, s2.ran) == (2, N_SMALL - 2)
    assert s1.config_hash == s2.config_hash


def test_crashing_trials_are_errors_never_successes(tmp_path) -> None:
    run_dir = tmp_path / "r"
    summary = run_benchmark(
        SMALL, run_dir, backend=FakeBackend(raise_on=("bowl",), default_success=1.0),
        progress=False,
    )  # fmt: skip
    results = load_results(run_dir)
    errors = [r for r in results.attempts if r["status"] == "error"]
    bowl_trials = [s for s in build_trials(SMALL) if "bowl" in s.objects]
    assert summary.errors == len(errors) == len(bowl_trials)
    assert all(r["success"] == "" and r["outcome"] == "" for r in errors)
    assert all("RuntimeError" in r["detail"] for r in errors)
    ok = [r for r in results.attempts if r["status"] == "ok"]
    assert ok and all(r["success"] == "1" for r in ok)
    # Errors are finished trials: a plain resume skips them, --retry-errors runs them again.
    fixed = FakeBackend(default_success=1.0)  # the cause is gone; same settings, same hash
    again = run_benchmark(SMALL, run_dir, backend=fixed, resume=True, progress=False)
    assert again.ran == 0
    retried = run_benchmark(
        SMALL, run_dir, backend=fixed, resume=True, retry_errors=True, progress=False
    )
    assert retried.ran == len(bowl_trials) and retried.errors == 0
    assert not load_results(run_dir).error_keys
    assert _keys(run_dir) == sorted(s.key for s in build_trials(SMALL))


def test_benchmark_command_says_when_the_trial_runner_is_missing(tmp_path, monkeypatch, capsys):
    from hsqbench.cli import main

    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", None)  # import fails
    code = main(["benchmark", "--protocol", "quick", "--run", str(tmp_path / "q"), "--jobs", "1"])
    err = capsys.readouterr().err
    assert code == 2
    assert "trial runner" in err and "not available" in err and "no trial was run" in err
    assert not (tmp_path / "q").exists()


def test_benchmark_command_argument_errors(tmp_path, capsys) -> None:
    from hsqbench.cli import main

    assert main(["benchmark", "--resume"]) == 2
    assert "--run RUN" in capsys.readouterr().err
    assert main(["benchmark", "--retry-errors", "--run", str(tmp_path / "x")]) == 2
    assert "--resume" in capsys.readouterr().err
    assert main(["benchmark", "--protocol", "nope", "--run", str(tmp_path / "x")]) == 2
    assert "nope" in capsys.readouterr().err


def test_benchmark_command_end_to_end_with_a_stand_in_backend(tmp_path, monkeypatch, capsys):
    """The command's own flow (run, report, exit codes); the trial runner is replaced."""
    import warnings

    import hsqbench.experiment.runner as runner_module
    from hsqbench.cli import main

    backends = iter([FakeBackend(interrupt_after=1), FakeBackend(raise_on=("foam_brick",))])
    monkeypatch.setattr(runner_module, "SimBackend", lambda name: next(backends))
    run_dir = tmp_path / "quick"
    args = ["benchmark", "--protocol", "quick", "--run", str(run_dir), "--jobs", "1"]
    assert main(args) == 130
    assert "--resume" in capsys.readouterr().err
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        code = main([*args, "--resume"])
    out, err = capsys.readouterr()
    assert code == 1  # the foam_brick trials failed with an error: a failing exit, said why
    assert "1 already done" in out and "tables.md" in out and "retry-errors" in err
    assert (run_dir / "tables.md").exists()


def test_unplaceable_draws_are_redrawn_recorded_and_kept_on_resume(tmp_path) -> None:
    import csv
    import json

    from hsqbench.experiment.seeds import packed_round_objects

    first = packed_round_objects(SMALL.packed.objects, 2, 0, 0)
    backend = FakeBackend(unplaceable=(first,))
    run_dir = tmp_path / "r"
    summary = run_benchmark(SMALL, run_dir, backend=backend, progress=False)
    assert summary.errors == 0  # the fake backend raises on an unplaceable round: none ran
    with open(run_dir / "rounds.csv") as f:
        rounds = [r for r in csv.DictReader(f) if r["trial_index"] == "0"]
    assert len(rounds) == 2 and len({r["objects"] for r in rounds}) == 1  # both planners
    assert rounds[0]["objects"] != ";".join(first)
    assert all(";".join(first) in r["detail"] and "redrawn" in r["detail"] for r in rounds)
    draws = json.loads((run_dir / "run.json").read_text())["packed_draws"]
    assert draws["s0/round/000"] == {
        "objects": rounds[0]["objects"].split(";"),
        "rejected": [list(first)],
    }
    assert all(d["objects"] != list(first) for d in draws.values())

    class Moved(FakeBackend):  # same settings, other placement (as if the hulls had changed)
        def placeable(self, objects, seed):
            return True

    with pytest.raises(ResultsError, match=r"round/000.*other objects"):
        run_benchmark(SMALL, run_dir, backend=Moved(unplaceable=(first,)), resume=True)
    again = run_benchmark(SMALL, run_dir, backend=backend, resume=True, progress=False)
    assert (again.skipped, again.ran) == (N_SMALL, 0)


def test_only_the_objects_of_the_chosen_experiments_are_prepared(tmp_path) -> None:
    config = ExperimentConfig(
        planners=("a",),
        isolated=IsolatedConfig(objects=("mug", "bowl"), attempts_per_object=1),
        packed=PackedConfig(objects=("apple", "mug", "pear"), rounds=1, objects_per_round=2),
    )
    backend = FakeBackend()
    run_benchmark(config, tmp_path / "all", backend=backend, progress=False)
    assert backend.prepared == ("mug", "bowl", "apple", "pear")
    run_benchmark(
        config, tmp_path / "iso", backend=backend, experiments=["isolated"], progress=False
    )
    assert backend.prepared == ("mug", "bowl")


def test_an_unknown_object_stops_the_run_before_any_trial(tmp_path) -> None:
    with pytest.raises(ValueError, match="unknown object"):
        run_benchmark(SMALL, tmp_path / "r", backend=FakeBackend(unknown=("bowl",)), progress=False)
    assert not (tmp_path / "r" / "attempts.csv").exists()


def test_an_object_that_cannot_be_built_is_recorded_skipped_and_retried(tmp_path, capsys) -> None:
    import json

    run_dir = tmp_path / "r"
    backend = FakeBackend(unbuildable=("bowl",))  # its trials would raise if they were run
    summary = run_benchmark(SMALL, run_dir, backend=backend, progress=False)
    assert "object 'bowl' cannot be used" in capsys.readouterr().err
    results = load_results(run_dir)
    errors = {r["trial_key"]: r["detail"] for r in results.attempts if r["status"] == "error"}
    with_bowl = {s.key for s in build_trials(SMALL) if "bowl" in s.objects}
    assert set(errors) == with_bowl and summary.errors == len(with_bowl) > 0
    assert all(
        "'bowl' cannot be used: fake backend: this mesh cannot be built" in d
        for d in errors.values()
    )
    assert all("--retry-errors" in d for d in errors.values())
    # Every other trial is the same as in a run where every object builds (same draws too).
    ref = tmp_path / "ref"
    run_benchmark(SMALL, ref, backend=FakeBackend(), progress=False)
    kept = [r for r in _comparable(ref) if r[0] not in with_bowl]
    assert [r for r in _comparable(run_dir) if r[0] not in with_bowl] == kept
    meta = json.loads((run_dir / "run.json").read_text())
    assert set(meta["sessions"][0]["unusable_objects"]) == {"bowl"}
    # Once the object builds, --retry-errors runs exactly those trials.
    again = run_benchmark(
        SMALL, run_dir, backend=FakeBackend(), resume=True, retry_errors=True, progress=False
    )
    assert (again.ran, again.errors) == (len(with_bowl), 0)
    assert _comparable(run_dir) == _comparable(ref)


def test_a_gzipped_committed_run_is_read_and_not_resumed(tmp_path) -> None:
    import gzip

    from hsqbench.experiment.report import load_run

    run_dir = tmp_path / "r"
    run_benchmark(SMALL, run_dir, backend=FakeBackend(), progress=False)
    plain = load_run(run_dir)
    csv_path = run_dir / "attempts.csv"
    (run_dir / "attempts.csv.gz").write_bytes(gzip.compress(csv_path.read_bytes()))
    csv_path.unlink()
    packed = load_run(run_dir)
    assert packed.attempts.equals(plain.attempts) and len(packed.attempts) > 0
    with pytest.raises(ResultsError, match="gunzip it to resume"):
        run_benchmark(SMALL, run_dir, backend=FakeBackend(), resume=True, progress=False)
