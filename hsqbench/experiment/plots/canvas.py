"""The figure every report plot draws on: matplotlib's Agg canvas without pyplot's global
state, constrained layout (labels kept inside the image), 150 dpi (readable in a README)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from hsqbench.planner.registry import PRIVILEGED

DPI = 150


def figure(width_in: float, height_in: float) -> Any:
    from matplotlib.figure import Figure  # Agg canvas, no pyplot global state

    return Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")


def span(counts: list[int]) -> str:
    """``"450"``, or ``"198-251"`` when the planners' counts differ."""
    lo, hi = min(counts), max(counts)
    return f"{lo}" if lo == hi else f"{lo}-{hi}"


def n_text(counts: list[int], what: str) -> str:
    """``"n = 450 attempts"``, or ``"n = 198-251 attempts"`` when the planners' counts differ."""
    return f"n = {span(counts)} {what}"


def row_order(planners: Iterable[str], present: Iterable[str]) -> list[str]:
    """The ``present`` planners in ``planners``' order, the privileged ones (the oracle: a
    ceiling, not a method) last, so every figure lists planners alike."""
    shown = set(present)
    mine = [p for p in dict.fromkeys(planners) if p in shown]
    return [p for p in mine if p not in PRIVILEGED] + [p for p in mine if p in PRIVILEGED]
