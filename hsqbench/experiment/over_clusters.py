"""A planner against a reference over clusters (objects, rounds): the difference of the pooled
rates, its cluster-bootstrap interval (:mod:`hsqbench.experiment.cluster`) and the paired swap
test over clusters (:mod:`hsqbench.experiment.sign_flip`). The claim it supports is about
clusters like these (new objects, new rounds), not only the presentations that ran."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hsqbench.experiment.cluster import MIN_CLUSTERS, cluster_interval, paired_ratio_interval
from hsqbench.experiment.sign_flip import swap_p


@dataclass(frozen=True)
class ClusterDifference:
    """sum(k_planner) / sum(n_planner) - sum(k_reference) / sum(n_reference) over ``clusters``
    clusters (fractions); the interval is NaN with fewer than :data:`MIN_CLUSTERS` clusters."""

    clusters: int
    difference: float
    low: float
    high: float
    p_value: float

    @classmethod
    def of(
        cls,
        k_planner: np.ndarray,
        n_planner: np.ndarray,
        k_reference: np.ndarray,
        n_reference: np.ndarray,
        confidence: float = 0.95,
    ) -> ClusterDifference:
        """From per-cluster counts (one entry per cluster, aligned)."""
        kp, np_, kr, nr = (np.asarray(a, dtype=float) for a in
                           (k_planner, n_planner, k_reference, n_reference))  # fmt: skip
        p = swap_p(kp, np_, kr, nr)
        difference = kp.sum() / np_.sum() - kr.sum() / nr.sum()
        low = high = np.nan
        if kp.size >= MIN_CLUSTERS:
            if np.array_equal(np_, nr):  # the same pairs: a ratio of (won - lost) to pairs
                low, high = cluster_interval(kp - kr, np_, confidence)
            else:
                low, high = paired_ratio_interval(kp, np_, kr, nr, confidence)
        return cls(int(kp.size), float(difference), float(low), float(high), p)
