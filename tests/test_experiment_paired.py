"""Paired differences: exact McNemar against hand counts, Newcombe's interval by coverage."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.experiment.paired import (
    BETTER,
    SAME,
    WORSE,
    PairedDifference,
    mcnemar_exact,
    newcombe_interval,
)


@pytest.mark.parametrize(
    ("won", "lost", "expected"),
    [
        (1, 6, 2 * (1 + 7) / 2**7),  # 2 P(X <= 1), X ~ Bin(7, 1/2): 16/128
        (0, 5, 2 / 2**5),  # both tails' single extreme outcomes
        (3, 3, 1.0),
        (0, 0, 1.0),  # no discordant pair: no evidence either way
        (10, 2, 2 * (1 + 12 + 66) / 2**12),  # 2 P(X <= 2), X ~ Bin(12, 1/2)
    ],
)
def test_mcnemar_matches_hand_computed_binomial_tails(won: int, lost: int, expected: float) -> None:
    assert mcnemar_exact(won, lost) == pytest.approx(expected, rel=1e-12)
    assert mcnemar_exact(lost, won) == pytest.approx(expected, rel=1e-12)  # two-sided


def test_counts_difference_and_verdicts_from_aligned_outcomes() -> None:
    planner = np.array([1, 1, 0, 0, 1, 0, 0, 0, 1, 1], dtype=bool)
    reference = np.array([1, 1, 1, 1, 1, 1, 1, 1, 0, 1], dtype=bool)
    d = PairedDifference.of(planner, reference)
    assert (d.both, d.only_planner, d.only_reference, d.neither) == (4, 1, 5, 0)
    assert d.difference == pytest.approx(-0.4) and d.n == 10
    assert d.p_value == pytest.approx(mcnemar_exact(1, 5))
    assert d.low <= d.difference <= d.high
    assert d.verdict == SAME  # p = 0.22 with ten pairs
    many = PairedDifference.of(np.tile(planner, 10), np.tile(reference, 10))
    assert many.verdict == WORSE and many.high < 0
    assert PairedDifference.of(np.tile(reference, 10), np.tile(planner, 10)).verdict == BETTER


def test_interval_mirrors_when_the_planners_swap() -> None:
    low, high = newcombe_interval(40, 3, 12, 5)
    swapped = newcombe_interval(40, 12, 3, 5)
    assert swapped == pytest.approx((-high, -low))
    assert low < (3 - 12) / 60 < high


def _coverage(joint: tuple[float, float, float, float], n: int, reps: int, seed: int) -> float:
    """Share of ``reps`` synthetic paired samples whose interval covers the true difference.
    ``joint``: probabilities of (both, planner only, reference only, neither)."""
    rng = np.random.default_rng(seed)
    truth = joint[1] - joint[2]
    hits = 0
    for counts in rng.multinomial(n, joint, size=reps):
        low, high = newcombe_interval(*(int(c) for c in counts), 0.95)
        hits += low <= truth <= high
    return hits / reps


@pytest.mark.parametrize(
    ("joint", "n"),
    [
        ((0.65, 0.05, 0.15, 0.15), 150),  # 70 % vs 80 %, positively correlated (paper scale)
        ((0.85, 0.02, 0.08, 0.05), 150),  # near the ceiling: 87 % vs 93 %
        ((0.30, 0.20, 0.20, 0.30), 60),  # no difference, many discordant pairs, small n
    ],
)
def test_newcombe_interval_covers_a_known_difference_at_about_95_percent(joint, n) -> None:
    # 2,000 samples: the Monte Carlo standard error of a 95 % coverage is 0.5 points.
    coverage = _coverage(joint, n, reps=2000, seed=44)
    assert 0.93 <= coverage <= 0.975


def test_bad_input_is_an_error() -> None:
    with pytest.raises(ValueError, match="at least one pair"):
        newcombe_interval(0, 0, 0, 0)
    with pytest.raises(ValueError, match="aligned"):
        PairedDifference.of(np.ones(3, bool), np.ones(4, bool))
    with pytest.raises(ValueError, match=">= 0"):
        mcnemar_exact(-1, 2)
