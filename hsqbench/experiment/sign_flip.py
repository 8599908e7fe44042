"""Paired tests over clusters (objects, rounds): a planner and a reference on the same clusters,
their labels swapped within a cluster under "no difference".

Pairs inside one cluster are not independent (the poses of one object, the objects of one
round), so the test resamples whole clusters. Under the null hypothesis that the planner and the
reference are exchangeable within each cluster, swapping the two planners' results of a cluster
is as likely as not, for every cluster independently; the p-value is the share of the 2^m swap
patterns of m clusters whose statistic is at least as far from 0 as the observed one
(Fisher's randomisation test; Good 2005, *Permutation, Parametric and Bootstrap Tests of
Hypotheses*, Section 3.1).

- Both planners have the same pairs in a cluster (paired success, removed objects, VGN-rule
  successes over the objects presented): the difference of the rates is sum(d_c) / sum(n_c)
  with d_c = (won - lost) pairs of cluster c, and a swap flips the sign of d_c. The null
  distribution of sum(+-d_c) is computed exactly, by convolving the m two-point distributions
  {-d_c, +d_c} (the d_c are integers), for any number of clusters: no random draws, so the
  p-value depends neither on a seed nor on the order of the clusters.
- The planners' denominators differ within a cluster (GSR of a round: each planner makes its own
  number of attempts): the statistic is the difference of two ratios of sums, and a swap
  exchanges a cluster's (successes, attempts) between the planners. scipy's
  ``permutation_test(permutation_type="samples")`` on one sample flips signs: it enumerates
  all 2^m patterns when 2^m <= :data:`N_DRAWS`, else draws :data:`N_DRAWS` of them with a fixed
  seed, the clusters put in a canonical order first so that their order in the input does not
  change the draws.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import permutation_test

#: Random swap patterns when the exact null distribution is not enumerated: the Monte Carlo
#: standard error of p is then sqrt(p (1 - p) / N), 0.0007 at p = 0.05.
N_DRAWS = 100_000
SEED = 0


def sign_flip_p(differences: np.ndarray) -> float:
    """Exact two-sided p of sum(d) under independent sign flips of the integer ``differences``
    (one per cluster): P(|sum(+-d_c)| >= |sum(d_c)|). 1.0 when every d_c is 0.

    Raises:
        ValueError: a difference is not an integer (or not finite), or the array is not 1-D.
    """
    d = np.asarray(differences, dtype=float)
    if d.ndim != 1:
        raise ValueError(f"one difference per cluster: a 1-D array, got shape {d.shape}")
    if not np.all(np.isfinite(d)) or np.any(d != np.round(d)):
        raise ValueError("sign_flip_p needs integer per-cluster differences (won - lost pairs)")
    steps = np.abs(d[d != 0]).astype(int)
    total = int(steps.sum())
    if total == 0:
        return 1.0
    # pmf[v + total] = P(sum of +-steps = v), built one cluster at a time.
    pmf = np.zeros(2 * total + 1)
    pmf[total] = 1.0
    for s in steps:
        pmf = 0.5 * (np.roll(pmf, s) + np.roll(pmf, -s))  # no wrap: |sum| <= total throughout
    observed = abs(int(d.sum()))
    values = np.abs(np.arange(-total, total + 1))
    return float(min(1.0, pmf[values >= observed].sum()))


def swap_p(
    k_planner: np.ndarray,
    n_planner: np.ndarray,
    k_reference: np.ndarray,
    n_reference: np.ndarray,
    seed: int = SEED,
) -> float:
    """Two-sided p of sum(k_planner) / sum(n_planner) - sum(k_reference) / sum(n_reference)
    under independent swaps of the two planners' (k, n) within each cluster (entries).

    Equal denominators in every cluster reduce it to :func:`sign_flip_p` of k_planner -
    k_reference (exact); otherwise scipy's sign-flip ``permutation_test`` (exact up to
    2^m = :data:`N_DRAWS`, else :data:`N_DRAWS` draws with ``seed``).

    Raises:
        ValueError: misaligned arrays, or a planner without any attempt over all clusters.
    """
    arrays = [np.asarray(a, dtype=float) for a in (k_planner, n_planner, k_reference, n_reference)]
    if any(a.shape != arrays[0].shape or a.ndim != 1 for a in arrays):
        raise ValueError(f"per-cluster arrays must align, got {[a.shape for a in arrays]}")
    kp, np_, kr, nr = arrays
    if np_.sum() <= 0 or nr.sum() <= 0:
        raise ValueError("each planner needs at least one attempt over the clusters")
    if np.array_equal(np_, nr):
        return sign_flip_p(kp - kr)
    # Canonical order: the same clusters in any order meet the same random draws.
    order = np.lexsort((nr, kr, np_, kp))
    kp, np_, kr, nr = kp[order], np_[order], kr[order], nr[order]

    def statistic(signed: np.ndarray, axis: int = -1) -> np.ndarray:
        # ``signed`` holds +-(cluster index + 1): the sign says whether the cluster is swapped.
        i = np.abs(signed).astype(int) - 1
        keep = signed > 0
        a_k, a_n = np.where(keep, kp[i], kr[i]), np.where(keep, np_[i], nr[i])
        b_k, b_n = np.where(keep, kr[i], kp[i]), np.where(keep, nr[i], np_[i])
        return a_k.sum(axis=axis) / a_n.sum(axis=axis) - b_k.sum(axis=axis) / b_n.sum(axis=axis)

    result = permutation_test(
        (np.arange(1, kp.size + 1, dtype=float),),
        statistic,
        permutation_type="samples",
        vectorized=True,
        n_resamples=N_DRAWS,
        batch=10_000,
        alternative="two-sided",
        rng=np.random.default_rng(seed),
    )
    return float(result.pvalue)
