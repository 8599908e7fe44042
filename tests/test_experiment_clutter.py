"""VGN/GIGA-rule clutter metrics recomputed from a run's rounds and attempts."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from hsqbench.experiment.cluster import cluster_interval
from hsqbench.experiment.clutter import clutter_table, render_clutter, vgn_round
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.report import load_run
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend


@pytest.mark.parametrize(
    ("outcomes", "expected"),
    [
        (["success", "dropped", "success"], (2, 3, False)),  # no cut: their rule ends it too
        (["success", "no_grasp_found", "success", "success"], (1, 1, True)),
        (["no_grasp_found", "success"], (0, 0, True)),  # round over before any grasp
        ([], (0, 0, False)),
    ],
)
def test_a_round_ends_before_its_first_attempt_without_a_grasp(outcomes, expected) -> None:
    assert vgn_round(outcomes, [o == "success" for o in outcomes]) == expected


def test_run_totals_follow_the_cut_rounds(tmp_path: Path) -> None:
    config = ExperimentConfig(
        planners=("hsq", "antipodal"),
        isolated=IsolatedConfig(enabled=False),
        packed=PackedConfig(
            objects=("mug", "bowl", "pear", "banana", "apple"), rounds=12, objects_per_round=4
        ),
    )
    backend = FakeBackend(success={"antipodal": 0.5})
    run_dir = tmp_path / "run"
    run_benchmark(config, run_dir, backend=backend, progress=False)
    table = clutter_table(load_run(run_dir)).set_index("planner")
    with open(run_dir / "attempts.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["planner"] == "antipodal"]
    by_round: dict[str, list[str]] = {}
    for r in sorted(rows, key=lambda r: (r["trial_key"], int(r["attempt_index"]))):
        by_round.setdefault(r["trial_key"], []).append(r["outcome"])
    k = n = cut = 0
    for outcomes in by_round.values():
        stop = outcomes.index("no_grasp_found") if "no_grasp_found" in outcomes else len(outcomes)
        k, n, cut = k + outcomes[:stop].count("success"), n + stop, cut + (stop < len(outcomes))
    row = table.loc["antipodal"]
    assert (row["vgn_successes"], row["vgn_attempts"], row["rounds_cut"]) == (k, n, cut)
    assert cut > 0  # the fake backend's failures include "no grasp found"
    assert row["declutter_percent"] == pytest.approx(100 * k / (12 * 4))
    # VGN's percent_cleared leaves out the rounds cut before their first grasp.
    empty = sum(1 for o in by_round.values() if o[0] == "no_grasp_found")
    assert row["vgn_percent_cleared"] == pytest.approx(100 * k / ((12 - empty) * 4))
    # Intervals over rounds: the cluster bootstrap of the rounds' counts, not Wilson.
    per = [
        (o[: o.index("no_grasp_found")] if "no_grasp_found" in o else o) for o in by_round.values()
    ]
    k_r = np.array([x.count("success") for x in per])
    low, high = cluster_interval(k_r, np.full(len(per), 4))
    assert (row["declutter_low_percent"], row["declutter_high_percent"]) == pytest.approx(
        (100 * low, 100 * high)
    )
    assert row["declutter_percent"] <= row["our_cr_percent"]
    # Paired to hsq over the same draws: the exact sign-flip test of the rounds' differences.
    assert row["dr_vs_reference_rounds"] == 12
    assert 0 <= row["dr_vs_reference_p"] <= row["dr_vs_reference_p_holm"] <= 1
    lines = render_clutter(load_run(run_dir), table.reset_index())
    assert any(x.startswith("| packed | antipodal |") for x in lines)


def test_vgn_percent_cleared_leaves_out_rounds_without_a_grasp() -> None:
    """Two rounds counted by hand: A (5 objects) S S F S F F; B (4 objects) ends at once with no
    grasp. GIGA: GSR 3/6, declutter 3/9; VGN's percent_cleared joins rounds to their grasps, so B
    drops out: 3/5."""
    import types

    import pandas as pd

    outcomes = {
        "packed/p/s0/round/000": ["success", "success", "empty_grasp", "success", "dropped",
                                  "empty_grasp"],
        "packed/p/s0/round/001": ["no_grasp_found"],
    }  # fmt: skip
    attempts = pd.DataFrame(
        [
            {"trial_key": k, "attempt_index": i, "outcome": o, "success": int(o == "success"),
             "status": "ok", "planner": "p"}
            for k, os in outcomes.items()
            for i, o in enumerate(os)
        ]
    )  # fmt: skip
    rounds = pd.DataFrame(
        {
            "trial_key": list(outcomes),
            "planner": ["p", "p"],
            "base_seed": [0, 0],
            "trial_index": [0, 1],
            "objects": ["a;b;c;d;e", "f;g;h;i"],
            "n_objects": [5, 4],
            "n_cleared": [3, 0],
            "status": ["ok", "ok"],
        }
    )
    data = types.SimpleNamespace(attempts=attempts, rounds=rounds, planners=["p"], confidence=0.95)
    row = clutter_table(data).iloc[0]
    assert (row["vgn_successes"], row["vgn_attempts"], row["rounds_cut"]) == (3, 6, 1)
    assert row["vgn_gsr_percent"] == pytest.approx(50.0)
    assert row["declutter_percent"] == pytest.approx(100 * 3 / 9)
    assert row["vgn_percent_cleared"] == pytest.approx(60.0)
    assert row["our_gsr_percent"] == pytest.approx(100 * 3 / 7)
