"""Paired comparison of two planners on the same presentations: the difference in success rate
with its interval, and the exact McNemar test.

Every planner in a run sees the same presentations (same seeds, same poses), so outcomes come in
pairs. Of n pairs, ``both`` succeeded for both planners, ``only_planner`` for the planner alone,
``only_reference`` for the reference alone, ``neither`` for none. The difference

    d = p_planner - p_reference = (only_planner - only_reference) / n

depends on the discordant pairs only, and so does its test:

- McNemar's exact test: under "no difference" each discordant pair goes either way with
  probability 1/2, so ``only_planner`` ~ Binomial(only_planner + only_reference, 1/2); the
  two-sided p-value is scipy's exact ``binomtest`` (McNemar 1947; Fagerland, Lydersen, Laake 2013,
  BMC Med Res Methodol 13:91, who find it conservative: a "better" or "worse" verdict from it is safe).
- The interval of d: Newcombe's hybrid score interval for paired proportions (Newcombe 1998,
  Statistics in Medicine 17:2635-2650, method 10): the Wilson intervals (l1, u1) of p_planner and
  (l2, u2) of p_reference combined with the correlation phi of the 2x2 table,

      L = d - sqrt((p1 - l1)^2 - 2 phi (p1 - l1)(u2 - p2) + (u2 - p2)^2)
      U = d + sqrt((u1 - p1)^2 - 2 phi (u1 - p1)(p2 - l2) + (p2 - l2)^2)

  with phi = (both * neither - only_planner * only_reference) / sqrt of the product of the four
  margins (0 when a margin is empty). Its coverage stays close to nominal down to small n and at
  rates near 0 or 1, where the Wald interval of d fails (compared with others in Fagerland, Lydersen,
  Laake 2014, Statistics in Medicine 33:2850-2875). scipy has no interval for paired proportions.

The verdict in words follows the test: "better" or "worse" when McNemar's p-value is below
1 - confidence (the sign of d says which), "not distinguishable" otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import binomtest

from hsqbench.experiment.stats import wilson_interval

BETTER, WORSE, SAME = "better", "worse", "not distinguishable"


def verdict_of(difference: float, p_value: float, confidence: float) -> str:
    """ "better" or "worse" (by the sign of ``difference``) when ``p_value`` < 1 - confidence,
    else "not distinguishable"; "—" without a test (NaN p)."""
    if not np.isfinite(p_value):
        return "—"
    if p_value >= 1.0 - confidence or difference == 0:
        return SAME
    return BETTER if difference > 0 else WORSE


def mcnemar_exact(only_planner: int, only_reference: int) -> float:
    """Two-sided exact McNemar p-value of the discordant counts (1.0 without discordant pairs)."""
    if only_planner < 0 or only_reference < 0:
        raise ValueError(f"discordant counts must be >= 0, got {only_planner} and {only_reference}")
    discordant = only_planner + only_reference
    if discordant == 0:
        return 1.0
    return float(binomtest(only_planner, discordant, 0.5).pvalue)


def newcombe_interval(
    both: int, only_planner: int, only_reference: int, neither: int, confidence: float = 0.95
) -> tuple[float, float]:
    """Newcombe's hybrid score interval (method 10) of p_planner - p_reference, in [-1, 1]."""
    n = both + only_planner + only_reference + neither
    if n < 1 or min(both, only_planner, only_reference, neither) < 0:
        raise ValueError(
            "a paired interval needs at least one pair and counts >= 0, got "
            f"{(both, only_planner, only_reference, neither)}"
        )
    p1, p2 = (both + only_planner) / n, (both + only_reference) / n
    l1, u1 = wilson_interval(both + only_planner, n, confidence)
    l2, u2 = wilson_interval(both + only_reference, n, confidence)
    margins = (
        (both + only_planner)
        * (only_reference + neither)
        * (both + only_reference)
        * (only_planner + neither)
    )
    phi = (both * neither - only_planner * only_reference) / math.sqrt(margins) if margins else 0.0
    d = p1 - p2
    lower = (p1 - l1) ** 2 - 2 * phi * (p1 - l1) * (u2 - p2) + (u2 - p2) ** 2
    upper = (u1 - p1) ** 2 - 2 * phi * (u1 - p1) * (p2 - l2) + (p2 - l2) ** 2
    return max(-1.0, d - math.sqrt(max(lower, 0.0))), min(1.0, d + math.sqrt(max(upper, 0.0)))


@dataclass(frozen=True)
class PairedDifference:
    """A planner against the reference over ``n`` paired presentations (fractions in [-1, 1])."""

    both: int
    only_planner: int
    only_reference: int
    neither: int
    low: float
    high: float
    p_value: float
    confidence: float

    @classmethod
    def of(
        cls, planner: np.ndarray, reference: np.ndarray, confidence: float = 0.95
    ) -> PairedDifference:
        """From two aligned success arrays (one entry per presentation, the same order)."""
        a, b = np.asarray(planner, dtype=bool), np.asarray(reference, dtype=bool)
        if a.shape != b.shape or a.ndim != 1:
            raise ValueError(
                f"paired outcomes need two aligned 1-D arrays, got {a.shape} and {b.shape}"
            )
        counts = (
            int((a & b).sum()),
            int((a & ~b).sum()),
            int((~a & b).sum()),
            int((~a & ~b).sum()),
        )
        low, high = newcombe_interval(*counts, confidence)
        return cls(*counts, low, high, mcnemar_exact(counts[1], counts[2]), confidence)

    @property
    def n(self) -> int:
        return self.both + self.only_planner + self.only_reference + self.neither

    @property
    def difference(self) -> float:
        return (self.only_planner - self.only_reference) / self.n

    @property
    def verdict(self) -> str:
        """ "better", "worse" or "not distinguishable" at the run's confidence level (of the
        unadjusted p; a table of several tests judges by its Holm-adjusted p instead)."""
        return verdict_of(self.difference, self.p_value, self.confidence)

    def summary_columns(self) -> dict[str, float | str]:
        """The difference, its interval (percentage points), p and verdict, as CSV columns."""
        return {
            "difference_pp": 100 * self.difference,
            "ci_low_pp": 100 * self.low,
            "ci_high_pp": 100 * self.high,
            "p_value": self.p_value,
            "verdict": self.verdict,
        }

    def percent(self) -> str:
        """``"-6.7 [-11.8, -1.9]"``: the difference and its interval in percentage points."""
        return f"{100 * self.difference:+.1f} [{100 * self.low:+.1f}, {100 * self.high:+.1f}]"
