"""Object-level uncertainty: a cluster bootstrap over objects, and the spread of per-object rates.

Ten poses of one object are not ten independent draws: a planner that cannot grasp a bowl fails
on most of its poses. A claim about *unseen objects* is a claim about the next object, so its
interval must come from the objects, not the attempts. The cluster bootstrap (Davison and Hinkley
1997, Section 3.8; Field and Welsh 2007, JRSS B 69:369-390) resamples whole objects with
replacement, keeps all their presentations, and recomputes the pooled rate
sum(successes) / sum(attempts) on each resample; the interval is scipy's ``bootstrap`` (BCa) of
that ratio. When outcomes are independent of the object it matches the per-attempt Wilson
interval; when they are decided by the object it is as wide as the number of objects allows.
The same resampling gives the interval of a paired difference (numerator: discordant pairs won
minus lost, per object), and, with rounds as clusters, the intervals of packed and pile rates
(the objects of one round share a scene and a sequence of grasps).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import bootstrap

#: Resamples of the cluster bootstrap: with 20,000 the bounds move by at most 0.44 points over
#: ten seeds on ycb3 and paper3-pile (docs/statistics.md). Verdicts come from the exact tests
#: (:mod:`hsqbench.experiment.sign_flip`), not from whether an interval holds 0.
N_RESAMPLES = 20_000
#: Fewer objects than this give no useful bootstrap (too few distinct resamples).
MIN_CLUSTERS = 5
#: Objects listed as the worst in the spread.
WORST = 5


def _per_cluster(arrays: tuple[np.ndarray, ...]) -> tuple[np.ndarray, ...]:
    """The per-cluster arrays checked and put in a canonical order (sorted by their values),
    so that the same clusters in any order meet the same resamples."""
    cols = tuple(np.asarray(a, dtype=float) for a in arrays)
    if any(c.shape != cols[0].shape or c.ndim != 1 for c in cols):
        raise ValueError(f"per-cluster arrays must align, got {[c.shape for c in cols]}")
    if cols[0].size < MIN_CLUSTERS:
        raise ValueError(
            f"a cluster bootstrap needs at least {MIN_CLUSTERS} clusters (objects), got "
            f"{cols[0].size}"
        )
    order = np.lexsort(cols[::-1])
    return tuple(c[order] for c in cols)


def _bootstrap(
    arrays: tuple[np.ndarray, ...], statistic, confidence: float, seed: int
) -> tuple[float, float]:
    """scipy's paired ``bootstrap`` over clusters (BCa; percentile where BCa is undefined)."""
    rng = np.random.default_rng(seed)
    with warnings.catch_warnings():  # BCa's degenerate-jackknife warning: handled below
        warnings.simplefilter("ignore")
        for method in ("BCa", "percentile"):
            low, high = bootstrap(
                arrays,
                statistic,
                paired=True,
                vectorized=True,
                n_resamples=N_RESAMPLES,
                confidence_level=confidence,
                method=method,
                rng=rng,
            ).confidence_interval
            if np.isfinite(low) and np.isfinite(high):
                break
    return float(low), float(high)


def cluster_interval(
    numerators: np.ndarray,
    denominators: np.ndarray,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Bootstrap interval of sum(numerators) / sum(denominators), resampling clusters (entries).

    ``numerators``: per cluster, e.g. successes (or discordant pairs won minus lost);
    ``denominators``: per cluster, its attempts (> 0). Fixed ``seed``, and the clusters sorted
    first: the same clusters in any order give the same interval.

    Raises:
        ValueError: fewer than :data:`MIN_CLUSTERS` clusters, misaligned arrays, or a cluster
            without attempts.
    """
    num, den = _per_cluster((numerators, denominators))
    if np.any(den <= 0):
        raise ValueError("every cluster needs at least one attempt")
    point = num.sum() / den.sum()
    if np.allclose(num / den, num[0] / den[0]):
        return float(point), float(point)  # every resample gives the same ratio

    def ratio(n: np.ndarray, d: np.ndarray, axis: int = -1) -> np.ndarray:
        return n.sum(axis=axis) / d.sum(axis=axis)

    return _bootstrap((num, den), ratio, confidence, seed)


def paired_ratio_interval(
    k_planner: np.ndarray,
    n_planner: np.ndarray,
    k_reference: np.ndarray,
    n_reference: np.ndarray,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Bootstrap interval of sum(k_planner) / sum(n_planner) - sum(k_reference) /
    sum(n_reference), resampling clusters (e.g. the GSR of two planners over the same rounds,
    each with its own number of attempts). Clusters sorted first, as in :func:`cluster_interval`.

    Raises:
        ValueError: fewer than :data:`MIN_CLUSTERS` clusters, misaligned arrays, or a planner
            without any attempt.
    """
    kp, np_, kr, nr = _per_cluster((k_planner, n_planner, k_reference, n_reference))
    if np.any(np_ < 0) or np.any(nr < 0) or np_.sum() <= 0 or nr.sum() <= 0:
        raise ValueError("each planner needs at least one attempt over the clusters")

    def difference(a_k, a_n, b_k, b_n, axis: int = -1) -> np.ndarray:
        with np.errstate(invalid="ignore", divide="ignore"):  # a resample without attempts
            return a_k.sum(axis=axis) / a_n.sum(axis=axis) - b_k.sum(axis=axis) / b_n.sum(axis=axis)

    return _bootstrap((kp, np_, kr, nr), difference, confidence, seed)


def rate_over_clusters(
    successes: np.ndarray, trials: np.ndarray, confidence: float = 0.95
) -> tuple[float, float]:
    """The interval of sum(successes) / sum(trials) over the clusters with trials (e.g. the GSR
    or CR of packed rounds); NaN with fewer than :data:`MIN_CLUSTERS` such clusters."""
    k, n = np.asarray(successes, dtype=float), np.asarray(trials, dtype=float)
    keep = n > 0
    if keep.sum() < MIN_CLUSTERS:
        return np.nan, np.nan
    return cluster_interval(k[keep], n[keep], confidence)


@dataclass(frozen=True)
class ObjectSpread:
    """How a planner's per-object rates spread: objects under 50 %, and the worst ones."""

    objects: int
    under_half: int
    worst: tuple[tuple[str, int, int], ...]  # (object, successes, attempts), worst first

    @classmethod
    def of(cls, per_object: pd.DataFrame) -> ObjectSpread:
        """From a frame with columns ``object``, ``successes``, ``attempts`` (one row each)."""
        rate = per_object["successes"] / per_object["attempts"]
        order = per_object.assign(rate=rate).sort_values(["rate", "object"], kind="stable")
        worst = tuple(
            (str(r.object), int(r.successes), int(r.attempts))
            for r in order.head(WORST).itertuples()
        )
        return cls(len(per_object), int((rate < 0.5).sum()), worst)

    def worst_text(self) -> str:
        return ", ".join(f"{o} {k}/{n}" for o, k, n in self.worst)
