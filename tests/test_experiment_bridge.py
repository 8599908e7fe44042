"""The bridge's paired steps on rounds counted by hand."""

from __future__ import annotations

import types

import pandas as pd
import pytest

from hsqbench.experiment.bridge import bridge_table, render_bridge


def _run(outcomes: dict[int, list[str]], presented: dict[int, int]) -> types.SimpleNamespace:
    keys = {i: f"packed/p/s0/round/{i:03d}" for i in outcomes}
    attempts = pd.DataFrame(
        [
            {"trial_key": keys[r], "attempt_index": i, "outcome": o,
             "success": int(o == "success"), "status": "ok", "planner": "p"}
            for r, os in outcomes.items()
            for i, o in enumerate(os)
        ]
    )  # fmt: skip
    rounds = pd.DataFrame(
        {
            "trial_key": [keys[r] for r in outcomes],
            "planner": "p",
            "base_seed": 0,
            "trial_index": list(outcomes),
            "objects": [f"draw{r}" for r in outcomes],
            "n_objects": [presented[r] for r in outcomes],
            "n_cleared": [os.count("success") for os in outcomes.values()],
            "status": "ok",
        }
    )
    return types.SimpleNamespace(attempts=attempts, rounds=rounds, planners=["p"])


def test_each_step_is_paired_with_the_one_before_round_by_round() -> None:
    s, f, ng = "success", "empty_grasp", "no_grasp_found"
    hand = _run({0: [s, s, f, s, f, f], 1: [s, s, ng]}, {0: 5, 1: 4})
    # The arm on the same draws: round 1 presents other objects (not paired), round 2 is new.
    arm = _run({0: [s, f, f], 1: [s, f, f], 2: [s]}, {0: 5, 1: 3, 2: 1})
    table = bridge_table([("hand", hand), ("arm", arm)])
    first, second = table.iloc[0], table.iloc[1]
    # Their counts: hand 5 successes in 8 grasps (the no-grasp step is not one), 5 of 9 objects.
    assert (first["gsr_k"], first["gsr_n"]) == (5, 8)
    assert first["declutter_percent"] == pytest.approx(100 * 5 / 9)
    assert "dr_vs_before_pp" not in first or pd.isna(first["dr_vs_before_pp"])
    # Round 0 alone pairs (round 1 was drawn alike but presented 3 objects, not 4).
    assert second["paired_rounds"] == 1
    assert second["dr_vs_before_pp"] == pytest.approx(100 * (1 / 5 - 3 / 5))
    lines = render_bridge(table)
    assert lines[2].startswith("| p | hand | 2 | 62.5 | 5/8 | 55.6 | — |")
    assert lines[3].startswith("| p | arm | 3 |")
