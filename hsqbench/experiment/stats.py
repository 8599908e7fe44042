"""Rates with Wilson score intervals (scipy's ``binomtest(...).proportion_ci``), and summary
statistics of timings.

Wilson interval of k successes in n Bernoulli trials at confidence 1 - a, with z = Phi^-1(1 - a/2)
and p = k / n:

    centre = (p + z^2 / (2n)) / (1 + z^2 / n)
    half   = z / (1 + z^2 / n) * sqrt(p (1 - p) / n + z^2 / (4 n^2))

It stays inside [0, 1] and is not degenerate at k = 0 or k = n, unlike the normal (Wald)
interval, which is why benchmark papers with 100-odd attempts use it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.stats import binomtest


def wilson_interval(successes: int, trials: int, confidence: float = 0.95) -> tuple[float, float]:
    """The Wilson score interval ``(low, high)`` of a proportion, as fractions in [0, 1].

    Raises:
        ValueError: ``trials`` < 1, ``successes`` outside [0, trials], or ``confidence`` not in (0, 1).
    """
    if trials < 1:
        raise ValueError(f"a rate needs at least one trial, got trials={trials}")
    if not 0 <= successes <= trials:
        raise ValueError(f"successes must be in [0, {trials}], got {successes}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    ci = binomtest(int(successes), int(trials)).proportion_ci(confidence, method="wilson")
    # The exact bounds at k = 0 and k = n are 0 and 1; clip rounding noise there.
    low = 0.0 if successes == 0 else max(0.0, float(ci.low))
    high = 1.0 if successes == trials else min(1.0, float(ci.high))
    return low, high


@dataclass(frozen=True)
class Rate:
    """``successes`` of ``trials`` with its Wilson interval (fractions in [0, 1])."""

    successes: int
    trials: int
    low: float
    high: float
    confidence: float

    @classmethod
    def of(cls, successes: int, trials: int, confidence: float = 0.95) -> Rate:
        low, high = wilson_interval(successes, trials, confidence)
        return cls(int(successes), int(trials), low, high, confidence)

    @property
    def value(self) -> float:
        return self.successes / self.trials

    def percent(self, digits: int = 1) -> str:
        """``"86.7 [79.9, 91.4] (130/150)"``: rate and interval in percent, then the counts."""
        return (
            f"{100 * self.value:.{digits}f} [{100 * self.low:.{digits}f}, "
            f"{100 * self.high:.{digits}f}] ({self.successes}/{self.trials})"
        )


@dataclass(frozen=True)
class TimeSummary:
    """Distribution of a duration, seconds."""

    n: int
    median_s: float
    p90_s: float
    mean_s: float
    max_s: float


def summarize_times(seconds: Sequence[float]) -> TimeSummary:
    """Median, 90th percentile (linear interpolation), mean and max of finite durations.

    Raises:
        ValueError: no finite value, or a negative duration.
    """
    x = np.asarray(seconds, dtype=float)
    x = x[np.isfinite(x)]
    if x.size == 0:
        raise ValueError("no finite durations to summarise")
    if np.any(x < 0):
        raise ValueError(f"durations must be >= 0 s, got min {x.min()}")
    return TimeSummary(
        n=int(x.size),
        median_s=float(np.median(x)),
        p90_s=float(np.percentile(x, 90)),
        mean_s=float(x.mean()),
        max_s=float(x.max()),
    )
