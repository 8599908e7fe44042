"""The append-only results store: row schema, atomic appends, repair after a kill, dedup."""

from __future__ import annotations

import csv
import json
import math

import pytest

from hsqbench.experiment.backend import TrialRun, execute_trial
from hsqbench.experiment.results import (
    ATTEMPT_COLUMNS,
    ROUND_COLUMNS,
    ResultsError,
    ResultStore,
    load_results,
    rows_for,
)
from hsqbench.experiment.seeds import TrialSpec
from hsqbench.sim.outcome import Attempt, Outcome, TrialResult
from tests.fake_backend import FakeBackend

ISO = TrialSpec("isolated", "hsq", 0, 2, ("mug",), 1234)
PACKED = TrialSpec("packed", "hsq", 0, 1, ("mug", "bowl", "apple"), 99)


def _run(spec: TrialSpec, **fake) -> TrialRun:
    return execute_trial(FakeBackend(**fake), spec)


def test_isolated_row_carries_the_attempt() -> None:
    run = _run(ISO)
    attempt = run.result.attempts[0]
    rows, round_row = rows_for(run, "abc123", "v1")
    assert round_row is None and len(rows) == 1
    row = rows[0]
    assert list(row) == list(ATTEMPT_COLUMNS)
    assert row["trial_key"] == "isolated/hsq/s0/mug/002"
    assert row["seed"] == "1234" and row["objects"] == "mug" and row["status"] == "ok"
    assert row["outcome"] == str(attempt.outcome)
    assert row["success"] == ("1" if attempt.success else "0")
    assert float(row["planning_s"]) == attempt.planning_s  # exact round trip
    assert float(row["h_gamma"]) == attempt.factors["h_gamma"]
    assert json.loads(row["factors"]) == attempt.factors
    assert row["config_hash"] == "abc123" and row["code_version"] == "v1"


def test_packed_round_rows() -> None:
    run = _run(PACKED)
    rows, round_row = rows_for(run, "h", "v")
    n = len(run.result.attempts)
    assert [r["attempt_index"] for r in rows] == [str(i) for i in range(n)]
    assert all(r["n_attempts"] == str(n) for r in rows)
    assert list(round_row) == list(ROUND_COLUMNS)
    assert round_row["n_objects"] == "3"
    assert round_row["n_cleared"] == str(len(run.result.objects_cleared))
    assert float(round_row["clearance_rate"]) == run.result.clearance_rate


def test_error_rows_are_not_attempts() -> None:
    run = _run(PACKED, raise_on=("bowl",))
    assert not run.ok and "RuntimeError" in run.error
    rows, round_row = rows_for(run, "h", "v")
    assert len(rows) == 1
    assert rows[0]["status"] == "error" and rows[0]["success"] == "" and rows[0]["outcome"] == ""
    assert rows[0]["attempt_index"] == "-1" and "fake backend failure" in rows[0]["detail"]
    assert round_row["status"] == "error" and round_row["n_cleared"] == ""


def test_fields_stay_on_one_line_and_nan_is_empty(tmp_path) -> None:
    run = TrialRun.failed(ISO, "boom\nsecond line\r\nthird")
    rows, _ = rows_for(run, "h", "v")
    assert "\n" not in rows[0]["detail"] and "second line" in rows[0]["detail"]
    ok = _run(ISO)
    ok.result.attempts[0].score = math.nan
    assert rows_for(ok, "h", "v")[0][0]["score"] == ""


def _store(tmp_path) -> ResultStore:
    store = ResultStore(tmp_path / "run")
    store.prepare()
    return store


def test_append_then_load_and_refuse_a_second_copy(tmp_path) -> None:
    store = _store(tmp_path)
    iso, packed = _run(ISO), _run(PACKED)
    store.append(iso, "h", "v")
    store.append(packed, "h", "v")
    results = load_results(store.run_dir)
    assert results.complete_keys == {ISO.key, PACKED.key}
    assert len(results.attempts) == 1 + len(packed.result.attempts)
    assert len(results.rounds) == 1
    with pytest.raises(ResultsError, match="already recorded"):
        store.append(iso, "h", "v")
    # a new store on the same folder knows it too
    again = ResultStore(store.run_dir)
    again.prepare()
    with pytest.raises(ResultsError, match="already recorded"):
        again.append(iso, "h", "v")


def test_partial_tail_and_incomplete_round_are_repaired(tmp_path) -> None:
    store = _store(tmp_path)
    store.append(_run(ISO), "h", "v")
    packed = _run(PACKED)
    att_rows, _ = rows_for(packed, "h", "v")
    # A kill between the attempt rows and the round row, then a kill mid-line.
    with open(store.attempts_path, "a", newline="") as f:
        csv.DictWriter(f, ATTEMPT_COLUMNS, lineterminator="\n").writerows(att_rows)
        f.write("isolated/hsq/s0/apple/000,isolated,hs")
    before = load_results(store.run_dir)
    assert before.partial_tail and PACKED.key in before.incomplete_keys
    assert before.complete_keys == {ISO.key}

    fresh = ResultStore(store.run_dir)
    kept = fresh.prepare()
    assert kept.complete_keys == {ISO.key}
    text = store.attempts_path.read_text()
    assert text.endswith("\n") and "apple" not in text and PACKED.key not in text
    fresh.append(packed, "h", "v")  # the round runs again and is counted once
    after = load_results(store.run_dir)
    assert after.complete_keys == {ISO.key, PACKED.key} and not after.incomplete_keys


def test_duplicates_are_counted_once(tmp_path) -> None:
    store = _store(tmp_path)
    iso = _run(ISO)
    store.append(iso, "h", "v")
    line = store.attempts_path.read_text().splitlines()[1]
    with open(store.attempts_path, "a") as f:
        f.write(line + "\n")
    results = load_results(store.run_dir)
    assert results.duplicate_keys == {ISO.key}
    assert len(results.attempts) == 1


def test_retry_errors_drops_error_trials_only(tmp_path) -> None:
    store = _store(tmp_path)
    store.append(_run(ISO, raise_on=("mug",)), "h", "v")
    store.append(_run(PACKED), "h", "v")
    kept = ResultStore(store.run_dir).prepare()
    assert kept.error_keys == {ISO.key}
    kept = ResultStore(store.run_dir).prepare(retry_errors=True)
    assert kept.complete_keys == {PACKED.key} and not kept.error_keys


def test_damaged_files_are_clear_errors(tmp_path) -> None:
    store = _store(tmp_path)
    store.append(_run(ISO), "h", "v")
    with open(store.attempts_path, "a") as f:
        f.write("only,three,fields\n")
    with pytest.raises(ResultsError, match="malformed row"):
        load_results(store.run_dir)
    store.attempts_path.write_text("trial_key,something_else\n")
    with pytest.raises(ResultsError, match="columns differ"):
        load_results(store.run_dir)


def test_one_writer_per_run_folder(tmp_path) -> None:
    a, b = ResultStore(tmp_path / "run"), ResultStore(tmp_path / "run")
    with a.locked(), pytest.raises(ResultsError, match="another hsqbench process"), b.locked():
        pass
    with b.locked():  # released
        pass


def test_backend_answering_another_trial_is_an_error() -> None:
    class WrongSeed(FakeBackend):
        def run_isolated(self, obj, seed, planner):
            return super().run_isolated(obj, seed + 1, planner)

    run = execute_trial(WrongSeed(), ISO)
    assert not run.ok and "another trial" in run.error


def test_backend_counting_an_object_both_cleared_and_lost_is_an_error() -> None:
    class Twice(FakeBackend):
        def run_packed(self, objects, seed, planner):
            result = super().run_packed(objects, seed, planner)
            result.objects_cleared = [objects[0]]
            result.objects_lost = [objects[0]]
            return result

    run = execute_trial(Twice(), PACKED)
    assert not run.ok and "must be distinct objects of the round" in run.error
    assert execute_trial(FakeBackend(), PACKED).ok


def test_rows_carry_how_the_scene_settled() -> None:
    """Every row of a trial (attempts and round) carries its scene's settling time and the
    largest object speed when the cameras first looked; an errored trial leaves them empty."""
    result = TrialResult("mug", 1234, "hsq", [Attempt(Outcome.SUCCESS, target="mug")])
    result.scene_settle_s, result.scene_max_speed = 1.25, 0.0041
    rows, _ = rows_for(TrialRun(ISO, result, None, 1.0, "w:1"), "h", "v")
    assert (rows[0]["scene_settle_s"], rows[0]["scene_max_speed"]) == ("1.25", "0.0041")
    packed = _run(PACKED)
    packed.result.scene_settle_s, packed.result.scene_max_speed = 2.5, 0.2
    rows, round_row = rows_for(packed, "h", "v")
    assert {r["scene_max_speed"] for r in rows} == {"0.2"}
    assert round_row["scene_settle_s"] == "2.5"
    rows, round_row = rows_for(_run(PACKED, raise_on=("bowl",)), "h", "v")
    assert rows[0]["scene_settle_s"] == "" and round_row["scene_max_speed"] == ""


def test_a_run_of_an_earlier_version_is_read_but_not_appended_to(tmp_path) -> None:
    """A results file written before the scene columns existed loads with them empty (reports
    of committed runs keep working); appending to it is refused with the fix named."""
    store = _store(tmp_path)
    store.append(_run(ISO), "h", "v")
    with open(store.attempts_path, newline="") as f:
        table = list(csv.DictReader(f))
    older = [c for c in ATTEMPT_COLUMNS if not c.startswith("scene_")]
    with open(store.attempts_path, "w", newline="") as f:
        writer = csv.DictWriter(f, older, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(table)
    [row] = load_results(store.run_dir).attempts
    assert row["scene_settle_s"] == "" and row["trial_key"] == ISO.key
    again = ResultStore(store.run_dir)
    with pytest.raises(ResultsError, match="use a new --run name"):
        again.prepare()


def test_rows_carry_the_grasp_pose_scores_and_stage_times() -> None:
    """The executed grasp in the world and in the object's frame (the two compose back), the
    planner's best scores and each stage's time, each field exact."""
    from dataclasses import replace

    import numpy as np

    from hsqbench.experiment.rows import numbers, pose_table
    from hsqbench.sim.recorded_pose import from_pose7

    run = _run(ISO)
    attempt = replace(
        run.result.attempts[0],
        object_pose=(0.5, 0.1, 0.02, np.cos(0.4), 0.0, 0.0, np.sin(0.4)),
        grasp_pose=(0.52, 0.08, 0.07, 0.0, 1.0, 0.0, 0.0),
        grasp_flipped=True,
        top_scores=(0.9, 0.8, 0.8),
        motion_planning_s=0.25,
        sim_time_s=12.5,
        planner_stages_s={"recovery": 0.5, "total": 0.75},
        ranks_tried=2,
    )
    run.result.attempts[0] = attempt
    [row], _ = rows_for(run, "h", "v")
    assert tuple(numbers(row["grasp_pose"])) == attempt.grasp_pose
    assert row["grasp_flipped"] == "1" and row["ranks_tried"] == "2"
    assert tuple(numbers(row["top_scores"])) == (0.9, 0.8, 0.8)
    assert float(row["motion_planning_s"]) == 0.25 and float(row["sim_time_s"]) == 12.5
    assert json.loads(row["planner_stages_s"]) == {"recovery": 0.5, "total": 0.75}
    op, orot = from_pose7(numbers(row["object_pose"]))
    lp, lrot = from_pose7(numbers(row["grasp_pose_object"]))
    gp, grot = from_pose7(attempt.grasp_pose)
    assert np.allclose(op + orot @ lp, gp) and np.allclose(orot @ lrot, grot)
    assert np.allclose(lp, orot.T @ [0.02, -0.02, 0.05])
    table = pose_table([row["grasp_pose"], ""])
    assert table.shape == (2, 7) and np.isnan(table[1]).all()


def test_a_packed_run_from_before_the_grasp_columns_loads_with_them_empty(tmp_path) -> None:
    """Committed runs are gzipped and may predate columns: both at once still read."""
    import gzip
    from dataclasses import replace

    import numpy as np

    from hsqbench.experiment.rows import pose_table

    store = _store(tmp_path)
    run = _run(ISO)
    run.result.attempts[0] = replace(
        run.result.attempts[0], grasp_pose=(0.52, 0.08, 0.07, 0.0, 1.0, 0.0, 0.0), ranks_tried=2
    )
    store.append(run, "h", "v")
    store.append(_run(PACKED), "h", "v")
    with open(store.attempts_path, newline="") as f:
        table = list(csv.DictReader(f))
    assert table[0]["grasp_pose"] and table[0]["ranks_tried"] == "2"
    # The columns that runs made before the grasp columns lack.
    newer = {"grasp_pose", "grasp_flipped", "grasp_pose_object", "top_scores"}
    newer |= {"motion_planning_s", "sim_time_s", "planner_stages_s", "ranks_tried"}
    older = [c for c in ATTEMPT_COLUMNS if c not in newer]
    with gzip.open(store.attempts_path.with_name("attempts.csv.gz"), "wt", newline="") as f:
        writer = csv.DictWriter(f, older, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(table)
    store.attempts_path.unlink()
    rows = load_results(store.run_dir).attempts
    assert len(rows) == len(table)
    assert all(r[c] == "" for r in rows for c in newer)
    assert np.isnan(pose_table([r["grasp_pose"] for r in rows])).all()
    assert [r["outcome"] for r in rows] == [r["outcome"] for r in table]  # its own columns


def test_every_column_is_documented() -> None:
    """docs/results-format.md has a row for each column of both files (meaning and units)."""
    import re
    from pathlib import Path

    doc = (Path(__file__).resolve().parents[1] / "docs" / "results-format.md").read_text()
    attempts, rounds = doc.split("## `rounds.csv`")
    documented = {
        part: set(re.findall(r"^\| ([^|]+) \|", text, re.M))
        for part, text in (("a", attempts), ("r", rounds))
    }
    names = {
        part: {n for cell in cells for n in re.findall(r"`(\w+)`", cell)}
        for part, cells in documented.items()
    }
    assert set(ATTEMPT_COLUMNS) <= names["a"], sorted(set(ATTEMPT_COLUMNS) - names["a"])
    assert set(ROUND_COLUMNS) <= names["r"], sorted(set(ROUND_COLUMNS) - names["r"])
