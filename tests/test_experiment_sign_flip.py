"""Paired tests over clusters (sign flips, swaps), Holm's adjustment, and verdicts that hold
whatever the bootstrap's seed or the order of the clusters."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import permutation_test

from hsqbench.experiment.cluster import cluster_interval, paired_ratio_interval
from hsqbench.experiment.holm import holm, holm_verdicts
from hsqbench.experiment.over_clusters import ClusterDifference
from hsqbench.experiment.sign_flip import sign_flip_p, swap_p


def test_exact_sign_flip_p_of_small_sets_known_by_hand() -> None:
    # 1+2+3+4 = 10 is reached only with every sign +, -10 only with every sign -: 2 of 16.
    assert sign_flip_p(np.array([1, 2, 3, 4])) == pytest.approx(2 / 16)
    assert sign_flip_p(np.array([1, 1, 1])) == pytest.approx(2 / 8)
    # +-3 +-1 +-2 takes 6, 2, 4, 0, 0, -4, -2, -6: |sum| >= |3 - 1 + 2| = 4 in 4 of 8.
    assert sign_flip_p(np.array([3, -1, 2])) == pytest.approx(4 / 8)
    assert sign_flip_p(np.array([0, 0, 0])) == 1.0
    assert sign_flip_p(np.array([-5])) == 1.0  # one cluster: either sign as likely


def test_sign_flip_p_matches_scipys_enumeration_and_needs_no_draws() -> None:
    rng = np.random.default_rng(3)
    d = rng.integers(-4, 5, size=12)
    exact = permutation_test((d.astype(float),), np.sum, permutation_type="samples",
                             n_resamples=np.inf).pvalue  # fmt: skip
    assert sign_flip_p(d) == pytest.approx(exact)
    many = rng.integers(-3, 8, size=45)  # 2^45 patterns: the convolution, not enumeration
    assert sign_flip_p(many) == sign_flip_p(rng.permutation(many)) < 1e-3


def test_sign_flip_rejects_fractions() -> None:
    with pytest.raises(ValueError, match="integer"):
        sign_flip_p(np.array([0.5, 1.0]))


def test_swap_test_of_unequal_denominators_known_by_hand() -> None:
    # Two rounds; planner 2/2 and 1/1, reference 0/1 and 0/2: difference 3/3 - 0/3 = 1.
    # Swapping one round gives 1/2 - 2/4 = 0 (either round); swapping both -1: p = 2/4.
    p = swap_p(np.array([2, 1]), np.array([2, 1]), np.array([0, 0]), np.array([1, 2]))
    assert p == pytest.approx(0.5)
    # Equal denominators: the exact sign-flip test of the differences.
    k1, k2, n = np.array([5, 3, 4, 2, 5]), np.array([2, 3, 1, 2, 0]), np.full(5, 5)
    assert swap_p(k1, n, k2, n) == pytest.approx(sign_flip_p(k1 - k2))


def test_holm_adjusts_by_hand() -> None:
    # Sorted 0.005, 0.01, 0.03, 0.04 times 4, 3, 2, 1 = 0.02, 0.03, 0.06, 0.04 -> monotone.
    adjusted = holm(np.array([0.01, 0.04, 0.03, 0.005]))
    assert adjusted == pytest.approx([0.03, 0.06, 0.06, 0.02])
    assert holm(np.array([0.6, 0.7])) == pytest.approx([1.0, 1.0])
    with_nan = holm(np.array([np.nan, 0.02, 0.5]))
    assert np.isnan(with_nan[0]) and with_nan[1:] == pytest.approx([0.04, 0.5])
    p, words = holm_verdicts(np.array([-3.0, 2.0, 1.0]), np.array([0.01, 0.02, 0.04]), 0.95)
    assert p == pytest.approx([0.03, 0.04, 0.04]) and words == ["worse", "better", "better"]
    # 0.02 alone would pass; as the least of three tests it is 3 x 0.02 = 0.06.
    p, words = holm_verdicts(np.array([-3.0, 2.0, 1.0]), np.array([0.02, 0.03, 0.5]), 0.95)
    assert p == pytest.approx([0.06, 0.06, 0.5]) and set(words) == {"not distinguishable"}


def _objects_like_ycb3() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """39 objects of 30 pairs; the planner loses a few pairs on most objects and wins some:
    a difference near the edge of significance, as Contact-GraspNet against hsq on ycb3."""
    rng = np.random.default_rng(11)
    won = rng.binomial(30, 0.05, size=39)
    lost = rng.binomial(30, 0.085, size=39)
    return won, lost, np.full(39, 30)


def test_verdicts_do_not_change_with_the_seed_or_the_order_of_clusters() -> None:
    won, lost, n = _objects_like_ycb3()
    base = ClusterDifference.of(won, n, lost, n)
    assert 0.005 < base.p_value < 0.2  # an edge case, not a landslide
    order = np.random.default_rng(5).permutation(won.size)
    shuffled = ClusterDifference.of(won[order], n, lost[order], n)
    assert (shuffled.p_value, shuffled.low, shuffled.high) == (base.p_value, base.low, base.high)
    a = cluster_interval(won - lost, n, seed=0)
    b = cluster_interval(won - lost, n, seed=1)
    assert a == pytest.approx(b, abs=0.005)  # 20,000 resamples: under half a point apart
    # Unequal denominators (GSR of rounds): the permutation test draws, with two seeds.
    attempts = n + np.random.default_rng(2).integers(-5, 5, size=n.size)
    p0 = swap_p(n - lost, n, n - won, attempts, seed=0)
    p1 = swap_p(n - lost, n, n - won, attempts, seed=1)
    p_shuffled = swap_p((n - lost)[order], n, (n - won)[order], attempts[order], seed=0)
    assert p_shuffled == p0 and abs(p0 - p1) < 0.005
    for family in ([base.p_value, 0.01], [p0, 0.01]):
        words = {
            tuple(holm_verdicts(np.array([-1.0, -1.0]), np.array(p), 0.95)[1])
            for p in (family, [family[0] + 0.003, 0.01], [family[0] - 0.003, 0.01])
        }
        assert len(words) == 1  # the verdicts do not hang on the Monte Carlo error


def test_interval_of_a_paired_ratio_difference() -> None:
    rng = np.random.default_rng(4)
    n_p, n_r = rng.integers(3, 8, size=30), rng.integers(3, 8, size=30)
    k_p, k_r = rng.binomial(n_p, 0.8), rng.binomial(n_r, 0.5)
    low, high = paired_ratio_interval(k_p, n_p, k_r, n_r)
    d = k_p.sum() / n_p.sum() - k_r.sum() / n_r.sum()
    assert low < d < high and low > 0 and high - low < 0.4
