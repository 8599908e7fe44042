"""Re-executing recorded grasps (hsqbench.experiment.replay, ``hsqbench replay``): a grasp
recorded in attempts.csv, executed again in its scene without planning, ends as recorded; the
replay executes the recorded pose (moved, it ends differently); rows without the grasp columns
are refused with the fix; ``--replan`` plans again and ends as recorded; the filters choose the
trials (isolated attempts, packed rounds) they name."""

from __future__ import annotations

import csv
import json
from dataclasses import replace

import numpy as np
import pytest

from hsqbench.cli import main
from hsqbench.config import to_dict
from hsqbench.experiment.backend import TrialRun
from hsqbench.experiment.replay import (
    RecordedGrasps,
    ReplayError,
    TrialFilter,
    recorded_grasp,
    replay_trial,
    run_rows,
    select_trials,
    trial_rows,
)
from hsqbench.experiment.results import RUN_FILE, ResultStore
from hsqbench.experiment.rows import numbers, rows_for
from hsqbench.experiment.seeds import TrialSpec
from hsqbench.sim.ik_types import FLIP_ABOUT_APPROACH
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.recorded_pose import from_pose7, pose7
from hsqbench.sim.trial import load_trial_config, run_isolated_trial

# hsq on the procedural box, seed 2: a success whose grasp was the first one motion-planned.
OBJECT, SEED = "proc_box", 2
KEY = f"isolated/hsq/s0/{OBJECT}/{SEED:03d}"


@pytest.fixture(scope="module")
def config():
    return replace(load_trial_config(), sensor="surface")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory, config):
    """A run folder holding one recorded trial, written as a benchmark writes it."""
    result = run_isolated_trial(OBJECT, SEED, "hsq", config)
    spec = TrialSpec("isolated", "hsq", 0, SEED, (OBJECT,), SEED)
    folder = tmp_path_factory.mktemp("replay") / "run"
    store = ResultStore(folder)
    with store.locked():
        store.prepare()
        store.append(TrialRun(spec, result, None, 1.0, "test:1"), "hash", "code")
    meta = {"backend": {"backend": "sim", "trial_config": to_dict(config)}}
    (folder / RUN_FILE).write_text(json.dumps(meta))
    return folder


def test_a_recorded_grasp_replays_to_the_same_outcome(run_dir, config):
    [row] = trial_rows(run_rows(run_dir), KEY)
    assert row["outcome"] == Outcome.SUCCESS and row["ranks_tried"] == "1"
    [again] = replay_trial([row], config)
    assert again.exact and again.same, again.detail
    # The same motion: the executed pose and the simulated time equal the recorded ones.
    assert np.allclose(again.attempt.grasp_pose, numbers(row["grasp_pose"]), atol=1e-12)
    assert again.attempt.sim_time_s == pytest.approx(float(row["sim_time_s"]), abs=1e-9)


def test_the_replay_executes_the_recorded_pose(run_dir, config):
    [row] = trial_rows(run_rows(run_dir), KEY)
    pose = numbers(row["grasp_pose"])
    pose[2] += 0.15  # 15 cm above the recorded grasp the fingers close on air
    [moved] = replay_trial([{**row, "grasp_pose": " ".join(str(float(x)) for x in pose)}], config)
    assert moved.replayed == Outcome.EMPTY_GRASP and not moved.same


def test_cli_replays_a_trial_and_says_it_matched(run_dir, capsys):
    assert main(["replay", "--run", str(run_dir), "--trial", KEY]) == 0
    out = capsys.readouterr().out
    assert f"{KEY} #0: success -> success (" in out
    assert "1 of 1 replayed attempts ended as recorded" in out


def test_cli_refuses_unknown_trials_and_bad_settings(run_dir, capsys):
    assert main(["replay", "--run", str(run_dir), "--trial", "isolated/hsq/s0/mug/000"]) == 2
    err = capsys.readouterr().err
    assert "no finished trial 'isolated/hsq/s0/mug/000'" in err and KEY in err
    assert main(["replay", "--run", str(run_dir), "--set", "execution.lift_height_m"]) == 2
    assert "write KEY=VALUE" in capsys.readouterr().err
    assert main(["replay", "--run", str(run_dir), "--outcome", "dropped"]) == 2
    assert "no finished trial matches" in capsys.readouterr().err


def test_cli_replans_and_writes_the_comparison(run_dir, tmp_path, capsys):
    out = tmp_path / "replay.csv"
    assert (
        main(
            [
                "replay",
                "--run",
                str(run_dir),
                "--replan",
                "--detail",
                "in the bin",
                "--csv",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert f"{KEY} #0: success -> success (" in text and " ~" not in text
    assert "1 of 1 replayed attempts ended as recorded" in text and f"wrote {out}" in text
    [row] = list(csv.DictReader(out.open()))
    assert (row["trial_key"], row["recorded"], row["replayed"], row["exact"]) == (
        KEY,
        "success",
        "success",
        "1",
    )


def test_cli_refuses_filters_that_match_nothing(run_dir, tmp_path, capsys):
    assert main(["replay", "--run", str(run_dir), "--detail", "no such detail"]) == 2
    assert "no finished trial matches" in capsys.readouterr().err
    # Its one attempt succeeded.
    assert main(["replay", "--run", str(run_dir), "--failed-graspable"]) == 2
    assert "no finished trial matches" in capsys.readouterr().err
    # A folder that is not there yet is made, as for every command's outputs.
    out = tmp_path / "new" / "x.csv"
    assert main(["replay", "--run", str(run_dir), "--csv", str(out)]) == 0
    assert out.is_file()


def _row(experiment, planner, seed, index, attempt, outcome, graspable, detail=""):
    key = f"{experiment}/{planner}/s{seed}/{'mug/' if experiment == 'isolated' else ''}{index:03d}"
    return {
        "trial_key": key,
        "experiment": experiment,
        "planner": planner,
        "attempt_index": str(attempt),
        "status": "ok",
        "outcome": outcome,
        "success": "1" if outcome == "success" else "0",
        "graspable": str(graspable),
        "detail": detail or ("in the bin" if outcome == "success" else "fell off"),
    }


ROWS = [
    _row("packed", "hsq", 0, 0, 0, "success", 1),  # all well
    _row("packed", "hsq", 0, 0, 1, "success", 1),
    _row("packed", "hsq", 0, 1, 0, "success", 1),
    _row("packed", "hsq", 0, 1, 1, "dropped", 1, "slipped: not in the bin"),  # graspable failure
    _row("packed", "hsq", 1, 0, 0, "dropped", 0),  # a failure on an ungraspable presentation
    _row("packed", "antipodal", 0, 1, 0, "dropped", 1),
    _row("isolated", "hsq", 0, 0, 0, "dropped", 1, "slipped: not in the bin"),
    {**_row("isolated", "hsq", 0, 1, 0, "dropped", 1), "status": "error"},  # did not run
]


def test_trials_are_chosen_once_each_in_run_order():
    assert select_trials(ROWS, TrialFilter()) == [
        "packed/hsq/s0/000",
        "packed/hsq/s0/001",
        "packed/hsq/s1/000",
        "packed/antipodal/s0/001",
        "isolated/hsq/s0/mug/000",
    ]


def test_filters_choose_by_planner_outcome_and_detail():
    assert select_trials(ROWS, TrialFilter(planner="antipodal")) == ["packed/antipodal/s0/001"]
    dropped = select_trials(ROWS, TrialFilter(outcome="dropped", planner="hsq"))
    assert dropped == ["packed/hsq/s0/001", "packed/hsq/s1/000", "isolated/hsq/s0/mug/000"]
    by_detail = select_trials(ROWS, TrialFilter(detail="not in the bin"))
    assert by_detail == ["packed/hsq/s0/001", "isolated/hsq/s0/mug/000"]


def test_failed_graspable_ignores_ungraspable_failures():
    chosen = select_trials(ROWS, TrialFilter(planner="hsq", failed_graspable=True))
    assert chosen == ["packed/hsq/s0/001", "isolated/hsq/s0/mug/000"]
    everyone = select_trials(ROWS, TrialFilter(failed_graspable=True))
    assert everyone == ["packed/hsq/s0/001", "packed/antipodal/s0/001", "isolated/hsq/s0/mug/000"]


def test_rows_of_runs_before_the_grasp_columns_are_refused():
    row = {"trial_key": KEY, "attempt_index": "0", "outcome": "dropped", "grasp_pose": ""}
    with pytest.raises(ReplayError, match=r"no grasp_pose: .*`hsqbench replay --run RUN --replan`"):
        recorded_grasp(row)
    assert recorded_grasp({**row, "outcome": "no_grasp_found"}) is None


def test_a_flipped_execution_is_turned_back_to_the_planners_grasp():
    rotation = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
    executed = pose7([0.4, 0.1, 0.05], rotation)
    row = {
        "trial_key": KEY,
        "attempt_index": "0",
        "outcome": "success",
        "grasp_pose": " ".join(map(repr, executed)),
        "grasp_flipped": "1",
        "width_m": "0.03",
        "score": "0.5",
    }
    grasp = recorded_grasp(row)
    assert np.allclose(grasp.rotation, rotation @ FLIP_ABOUT_APPROACH)
    assert np.allclose(grasp.position, [0.4, 0.1, 0.05]) and grasp.width == 0.03
    planner = RecordedGrasps([grasp, None])
    assert len(planner.plan(None, None).grasps) == 1
    assert planner.plan(None, None).grasps == [] and planner.plan(None, None).grasps == []


def test_pose_records_round_trip():
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))
    position, rotation = from_pose7(pose7([0.1, -0.2, 0.3], q))
    assert np.allclose(position, [0.1, -0.2, 0.3]) and np.allclose(rotation, q)
    assert pose7([0, 0, 0], np.eye(3))[3:] == (1.0, 0.0, 0.0, 0.0)
    with pytest.raises(ValueError, match="7 finite numbers"):
        from_pose7([0.0, 1.0])


@pytest.mark.slow
def test_a_packed_round_replays_attempt_by_attempt_up_to_the_one_asked(config):
    from hsqbench.sim.trial import run_packed_round

    objects = ("proc_box", "proc_cylinder", "proc_sphere")
    result = run_packed_round(list(objects), 3, "hsq", config)
    assert len(result.attempts) >= 2
    spec = TrialSpec("packed", "hsq", 0, 3, objects, 3)
    rows, _ = rows_for(TrialRun(spec, result, None, 1.0, "test:1"), "hash", "code")
    again = replay_trial(rows, config, upto=1)
    assert [a.index for a in again] == [0, 1]
    assert all(a.same for a in again if a.exact), [(a.recorded, a.replayed) for a in again]
