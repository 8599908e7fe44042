"""Wilson intervals against known values and an independent root-finding solution."""

from __future__ import annotations

import math

import pytest
from scipy.optimize import brentq
from scipy.stats import norm

from hsqbench.experiment.stats import Rate, summarize_times, wilson_interval


def _wilson_by_roots(k: int, n: int, confidence: float) -> tuple[float, float]:
    """The Wilson bounds as the roots of |k/n - p| = z sqrt(p (1 - p) / n) (score test)."""
    z = norm.ppf(0.5 + confidence / 2)
    phat = k / n

    def f(p: float) -> float:
        return (phat - p) ** 2 - z * z * p * (1 - p) / n

    inner = min(max(phat, 1e-12), 1 - 1e-12)  # f < 0 here; the roots lie on either side
    low = 0.0 if k == 0 else brentq(f, 1e-12, inner, xtol=1e-14)
    high = 1.0 if k == n else brentq(f, inner, 1 - 1e-12, xtol=1e-14)
    return low, high


def test_known_values_8_of_10() -> None:
    low, high = wilson_interval(8, 10)
    assert round(low, 4) == 0.4902
    assert round(high, 4) == 0.9433


@pytest.mark.parametrize(
    ("k", "n", "expected"),
    [(0, 10, (0.0, 0.2775)), (10, 10, (0.7225, 1.0)), (144, 150, (0.9155, 0.9815))],
)
def test_known_edges_and_paper_scale(k: int, n: int, expected: tuple[float, float]) -> None:
    low, high = wilson_interval(k, n)
    assert (round(low, 4), round(high, 4)) == expected


@pytest.mark.parametrize("confidence", [0.8, 0.95, 0.99])
@pytest.mark.parametrize(("k", "n"), [(0, 1), (1, 1), (3, 7), (50, 100), (149, 150), (0, 150)])
def test_matches_score_test_roots(k: int, n: int, confidence: float) -> None:
    low, high = wilson_interval(k, n, confidence)
    ref_low, ref_high = _wilson_by_roots(k, n, confidence)
    assert low == pytest.approx(ref_low, abs=1e-9)
    assert high == pytest.approx(ref_high, abs=1e-9)
    assert 0.0 <= low <= k / n <= high <= 1.0


def test_wider_with_confidence_and_narrower_with_n() -> None:
    lo95, hi95 = wilson_interval(8, 10, 0.95)
    lo99, hi99 = wilson_interval(8, 10, 0.99)
    assert lo99 < lo95 and hi99 > hi95
    lo, hi = wilson_interval(80, 100)
    assert hi - lo < hi95 - lo95


@pytest.mark.parametrize(
    ("k", "n", "confidence", "needle"),
    [(0, 0, 0.95, "at least one"), (11, 10, 0.95, "successes"), (-1, 10, 0.95, "successes"),
     (5, 10, 1.0, "confidence")],
)  # fmt: skip
def test_bad_input_is_an_error(k: int, n: int, confidence: float, needle: str) -> None:
    with pytest.raises(ValueError, match=needle):
        wilson_interval(k, n, confidence)


def test_rate_formats_percent_and_counts() -> None:
    rate = Rate.of(8, 10)
    assert rate.value == 0.8
    assert rate.percent() == "80.0 [49.0, 94.3] (8/10)"


def test_time_summary() -> None:
    s = summarize_times([1.0, 2.0, 3.0, 4.0, float("nan"), 10.0])
    assert s.n == 5 and s.median_s == 3.0 and s.max_s == 10.0
    assert s.p90_s == pytest.approx(4.0 + 0.6 * 6.0)  # linear interpolation between 4 and 10
    assert math.isclose(s.mean_s, 4.0)
    with pytest.raises(ValueError, match="no finite"):
        summarize_times([float("nan")])
    with pytest.raises(ValueError, match=">= 0"):
        summarize_times([1.0, -0.5])
