"""Graspability in the tables: shared scenes only, the oracle's coverage, and what planners
grasped of what it calls ungraspable."""

from __future__ import annotations

import pandas as pd
import pytest

from hsqbench.experiment.graspable import (
    coverage_from_rows,
    gsr_graspable,
    ungraspable_successes,
)


def _attempt(exp, planner, seed, objects, target, success, graspable):
    return {
        "experiment": exp,
        "planner": planner,
        "seed": seed,
        "objects": objects,
        "target": target,
        "success": success,
        "graspable": graspable,
        "status": "ok",
    }


ATTEMPTS = pd.DataFrame(
    [
        # Isolated seed 1: ungraspable by the oracle, hsq grasped it anyway.
        _attempt("isolated", "hsq", 1, "knife", "knife", 1, 0),
        _attempt("isolated", "oracle", 1, "knife", "", 0, 0),
        # Isolated seed 2: graspable, both grasped it.
        _attempt("isolated", "hsq", 2, "mug", "mug", 1, 1),
        _attempt("isolated", "oracle", 2, "mug", "mug", 1, 1),
        # A packed round: hsq's second attempt sees its own scene (graspable there = 0).
        _attempt("packed", "hsq", 7, "a;b", "a", 1, 1),
        _attempt("packed", "hsq", 7, "a;b", "b", 1, 0),
        _attempt("packed", "oracle", 7, "a;b", "a", 1, 1),
        _attempt("packed", "oracle", 7, "a;b", "", 0, 1),
    ]
)
ROUNDS = pd.DataFrame(
    [
        {"trial_key": f"packed/{p}/s0/round/0", "planner": p, "seed": 7, "objects": "a;b",
         "objects_graspable": "a", "objects_cleared": c, "status": "ok"}
        for p, c in (("hsq", "a;b"), ("oracle", "a"))
    ]
)  # fmt: skip


def test_coverage_counts_what_some_planner_grasped_against_the_shared_scene():
    cov = coverage_from_rows(ATTEMPTS, ROUNDS)
    # Isolated: knife (not covered), mug (covered); packed: a (covered), b (not: the round's
    # initial scene says only a is graspable, whatever hsq's later scene said).
    assert cov.parts == {"isolated": (1, 2), "packed": (1, 2)}
    assert "50.0 %" in cov.line("isolated")


def test_successes_on_what_the_oracle_calls_ungraspable_per_planner():
    t = ungraspable_successes(ATTEMPTS, ROUNDS).set_index(["experiment", "planner"])
    assert tuple(t.loc[("isolated", "hsq")]) == (1, 1)
    assert tuple(t.loc[("isolated", "oracle")]) == (0, 1)
    assert tuple(t.loc[("packed", "hsq")]) == (1, 1)  # b: not graspable at the start
    assert tuple(t.loc[("packed", "oracle")]) == (0, 1)


def test_packed_gsr_is_not_conditioned_on_a_planners_own_scene():
    packed = ATTEMPTS[ATTEMPTS["experiment"] == "packed"]
    with pytest.raises(ValueError, match="isolated"):
        gsr_graspable(packed, 0.95)
    iso = ATTEMPTS[(ATTEMPTS["experiment"] == "isolated") & (ATTEMPTS["planner"] == "hsq")]
    assert gsr_graspable(iso, 0.95).trials == 1
