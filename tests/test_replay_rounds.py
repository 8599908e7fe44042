"""bench/replay_rounds.py: which recorded packed rounds a replay selects."""

from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

import pandas as pd
import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


@pytest.fixture(scope="module")
def replay_rounds():
    sys.path.insert(0, str(BENCH))
    try:
        spec = importlib.util.spec_from_file_location("replay_rounds", BENCH / "replay_rounds.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(BENCH))
    return module


def _round(planner: str, base_seed: int, index: int) -> dict:
    return {
        "trial_key": f"packed/{planner}/s{base_seed}/round/{index:03d}",
        "planner": planner,
        "base_seed": base_seed,
        "trial_index": index,
        "seed": 100 * base_seed + index,
        "objects": "a;b",
    }


def _attempt(planner: str, base_seed: int, index: int, graspable: int, success: int) -> dict:
    return {
        "experiment": "packed",
        "planner": planner,
        "base_seed": base_seed,
        "trial_index": index,
        "attempt_index": 0,
        "graspable": graspable,
        "success": success,
        "outcome": "success" if success else "dropped",
    }


@pytest.fixture
def run(tmp_path: Path) -> Path:
    rounds = [_round("hsq", 0, 0), _round("hsq", 0, 1), _round("hsq", 1, 0)]
    rounds.append(_round("antipodal", 0, 1))
    attempts = [
        _attempt("hsq", 0, 0, 1, 1),  # all well
        _attempt("hsq", 0, 1, 1, 0),  # a graspable failure
        _attempt("hsq", 1, 0, 0, 0),  # a failure on an ungraspable presentation
        _attempt("antipodal", 0, 1, 1, 0),
    ]
    pd.DataFrame(rounds).to_csv(tmp_path / "rounds.csv", index=False)
    isolated = dict(_attempt("hsq", 0, 0, 1, 0), experiment="isolated")
    pd.DataFrame([*attempts, isolated]).to_csv(tmp_path / "attempts.csv", index=False)
    return tmp_path


def _args(**kw) -> argparse.Namespace:
    base = {"experiment": "packed", "planner": "hsq", "rounds": [], "failed_graspable": False}
    return argparse.Namespace(**{**base, **kw})


def _keys(rounds: pd.DataFrame) -> list[str]:
    return [f"{r.planner} {r.base_seed}/{r.trial_index}" for r in rounds.itertuples()]


def test_planner_filter_keeps_its_rounds_and_packed_attempts(replay_rounds, run) -> None:
    rounds, attempts = replay_rounds.select_rounds(run, _args())
    assert _keys(rounds) == ["hsq 0/0", "hsq 0/1", "hsq 1/0"]
    assert set(attempts.experiment) == {"packed"} and set(attempts.planner) == {"hsq"}


def test_rounds_by_key(replay_rounds, run) -> None:
    rounds, _ = replay_rounds.select_rounds(run, _args(rounds=["1/0", "0/1"]))
    assert _keys(rounds) == ["hsq 0/1", "hsq 1/0"]


def test_failed_graspable_ignores_ungraspable_failures(replay_rounds, run) -> None:
    rounds, _ = replay_rounds.select_rounds(run, _args(failed_graspable=True))
    assert _keys(rounds) == ["hsq 0/1"]
    rounds, _ = replay_rounds.select_rounds(run, _args(planner="", failed_graspable=True))
    assert _keys(rounds) == ["hsq 0/1", "antipodal 0/1"]
