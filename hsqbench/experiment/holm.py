"""Multiplicity: Holm's step-down adjustment of a family of p-values (Holm 1979, Scand. J.
Statist. 6:65-70).

A table that tests seven planners against a reference makes seven tests; at 0.05 each, the
chance that at least one "better" or "worse" is due to chance alone is up to 30 %. Holm's
adjustment keeps that family-wise error at the nominal level under any dependence between the
tests, and rejects at least what Bonferroni rejects. With the m p-values sorted,
p_(1) <= ... <= p_(m), the adjusted ones are

    p~_(i) = min(1, max over j <= i of (m - j + 1) p_(j))

and a test is significant when its adjusted p is below 1 - confidence. (statsmodels'
``multipletests(method="holm")`` computes the same; the project does not depend on statsmodels
for these four lines.) Missing p-values (NaN: no test in that row) are not in the family.
"""

from __future__ import annotations

import numpy as np


def holm(p_values: np.ndarray) -> np.ndarray:
    """Holm-adjusted p-values, in the input's order; NaN stays NaN and is not counted.

    Raises:
        ValueError: a p-value outside [0, 1].
    """
    p = np.asarray(p_values, dtype=float)
    out = np.full(p.shape, np.nan)
    tested = np.flatnonzero(np.isfinite(p))
    if tested.size == 0:
        return out
    values = p[tested]
    if np.any((values < 0) | (values > 1)):
        raise ValueError(f"p-values must be in [0, 1], got {values.min()} to {values.max()}")
    order = np.argsort(values, kind="stable")
    m = values.size
    stepped = np.maximum.accumulate((m - np.arange(m)) * values[order])
    out[tested[order]] = np.minimum(stepped, 1.0)
    return out


def holm_verdicts(
    differences: np.ndarray, p_values: np.ndarray, confidence: float
) -> tuple[np.ndarray, list[str]]:
    """(Holm-adjusted p, verdict words from it) of one family of tests, in the input's order."""
    from hsqbench.experiment.paired import verdict_of

    adjusted = holm(p_values)
    words = [
        verdict_of(float(d), float(p), confidence)
        for d, p in zip(np.asarray(differences, dtype=float), adjusted, strict=True)
    ]
    return adjusted, words
