"""The cluster bootstrap over objects against the per-attempt Wilson interval, and the spread."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from hsqbench.experiment.cluster import ObjectSpread, cluster_interval
from hsqbench.experiment.stats import wilson_interval

OBJECTS, POSES = 40, 30


def test_matches_wilson_when_outcomes_are_independent_of_the_object() -> None:
    rng = np.random.default_rng(7)
    k = rng.binomial(POSES, 0.7, size=OBJECTS)
    n = np.full(OBJECTS, POSES)
    low, high = cluster_interval(k, n)
    w_low, w_high = wilson_interval(int(k.sum()), int(n.sum()))
    assert low == pytest.approx(w_low, abs=0.012) and high == pytest.approx(w_high, abs=0.012)
    assert 0.75 < (high - low) / (w_high - w_low) < 1.3


def test_widens_when_the_object_decides_the_outcome() -> None:
    rng = np.random.default_rng(7)
    k = np.where(rng.random(OBJECTS) < 0.7, POSES, 0)  # every pose of an object alike
    n = np.full(OBJECTS, POSES)
    low, high = cluster_interval(k, n)
    w_low, w_high = wilson_interval(int(k.sum()), int(n.sum()))
    assert (high - low) > 3 * (w_high - w_low)
    assert low < k.sum() / n.sum() < high


def test_same_rate_on_every_object_has_no_spread_and_the_seed_fixes_it() -> None:
    assert cluster_interval(np.full(6, 3), np.full(6, 10)) == (0.3, 0.3)
    k, n = np.array([1, 5, 9, 3, 10, 0]), np.full(6, 10)
    assert cluster_interval(k, n, seed=3) == cluster_interval(k, n, seed=3)


def test_differences_can_be_negative() -> None:
    low, high = cluster_interval(np.array([-3, -1, -4, 0, -2, -5, 1]), np.full(7, 10))
    assert -0.5 < low < high < 0.1


def test_bad_input_is_an_error() -> None:
    with pytest.raises(ValueError, match="at least 5 clusters"):
        cluster_interval(np.ones(3), np.ones(3))
    with pytest.raises(ValueError, match="align"):
        cluster_interval(np.ones(6), np.ones(5))
    with pytest.raises(ValueError, match="at least one attempt"):
        cluster_interval(np.ones(6), np.array([1, 1, 1, 1, 1, 0]))


def test_spread_counts_objects_under_half_and_lists_the_worst_first() -> None:
    per = pd.DataFrame(
        {
            "object": ["a", "b", "c", "d", "e", "f", "g"],
            "successes": [10, 4, 0, 5, 9, 2, 1],
            "attempts": [10, 10, 10, 10, 10, 10, 2],
        }
    )
    spread = ObjectSpread.of(per)
    assert spread.objects == 7 and spread.under_half == 3  # b, c, f (d is 50 %, g 50 %)
    assert [w[0] for w in spread.worst] == ["c", "f", "b", "d", "g"]
    assert spread.worst_text().startswith("c 0/10, f 2/10")
