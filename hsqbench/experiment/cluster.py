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
minus lost, per object).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy.stats import bootstrap

#: Resamples of the cluster bootstrap; its Monte Carlo error is then well under 0.5 points.
N_RESAMPLES = 4999
#: Fewer objects than this give no useful bootstrap (too few distinct resamples).
MIN_CLUSTERS = 5
#: Objects listed as the worst in the spread.
WORST = 5


def cluster_interval(
    numerators: np.ndarray,
    denominators: np.ndarray,
    confidence: float = 0.95,
    seed: int = 0,
) -> tuple[float, float]:
    """Bootstrap interval of sum(numerators) / sum(denominators), resampling clusters (entries).

    ``numerators``: per cluster, e.g. successes (or discordant pairs won minus lost);
    ``denominators``: per cluster, its attempts (> 0). Fixed ``seed``: the same run gives the
    same interval.

    Raises:
        ValueError: fewer than :data:`MIN_CLUSTERS` clusters, misaligned arrays, or a cluster
            without attempts.
    """
    num = np.asarray(numerators, dtype=float)
    den = np.asarray(denominators, dtype=float)
    if num.shape != den.shape or num.ndim != 1:
        raise ValueError(f"per-cluster arrays must align, got {num.shape} and {den.shape}")
    if num.size < MIN_CLUSTERS:
        raise ValueError(
            f"a cluster bootstrap needs at least {MIN_CLUSTERS} clusters (objects), got {num.size}"
        )
    if np.any(den <= 0):
        raise ValueError("every cluster needs at least one attempt")
    point = num.sum() / den.sum()
    if np.allclose(num / den, num[0] / den[0]):
        return float(point), float(point)  # every resample gives the same ratio

    def ratio(n: np.ndarray, d: np.ndarray, axis: int = -1) -> np.ndarray:
        return n.sum(axis=axis) / d.sum(axis=axis)

    rng = np.random.default_rng(seed)
    with warnings.catch_warnings():  # BCa's degenerate-jackknife warning: handled below
        warnings.simplefilter("ignore")
        res = bootstrap(
            (num, den),
            ratio,
            paired=True,
            vectorized=True,
            n_resamples=N_RESAMPLES,
            confidence_level=confidence,
            rng=rng,
        )
        low, high = res.confidence_interval
        if not (np.isfinite(low) and np.isfinite(high)):  # BCa undefined: percentile instead
            low, high = bootstrap(
                (num, den),
                ratio,
                paired=True,
                vectorized=True,
                n_resamples=N_RESAMPLES,
                confidence_level=confidence,
                method="percentile",
                rng=rng,
            ).confidence_interval
    return float(low), float(high)


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
