"""Grasp ordering and de-duplication: pure functions on a planner's grasps (anything with
``position`` (3,), ``rotation`` (3, 3) and ``score``)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class OrderingConfig:
    """How grasps are ordered and de-duplicated (``ordering:`` of ``configs/trial.yaml``).

    Attributes:
        tie_window: grasps looked at per rank tried when ordering ties.
        easy_approach_outward: weight of "away from the robot" against "down" in the
            direction the arm reaches most easily.
        same_position_m: grasp points closer than this (rounded to it) are the same grasp.
        same_axis: approach and closing axes equal to this (rounded, unit vectors) are the same.
    """

    tie_window: int = 8
    easy_approach_outward: float = 0.4
    same_position_m: float = 0.001
    same_axis: float = 0.01

    def __post_init__(self) -> None:
        if self.tie_window < 1:
            raise ValueError(f"ordering.tie_window must be >= 1, got {self.tie_window}")
        if not (self.same_position_m > 0 and self.same_axis > 0):
            raise ValueError("ordering.same_position_m and same_axis must be positive")


def execution_order(grasps: Sequence[Any], window: int, outward_weight: float = 0.4) -> list[int]:
    """Ranks of the first ``window`` grasps in the order they are tried: by score, best first;
    among equal scores (the rolls of one closing line score the same, and the planner leaves
    their order arbitrary) the approach nearest "down and away from the robot" first, the
    direction the arm reaches most easily."""
    n = min(window, len(grasps))
    keys = []
    for r in range(n):
        g = grasps[r]
        p, a = np.asarray(g.position), np.asarray(g.rotation)[:, 2]
        radial = np.array([p[0], p[1], 0.0]) / max(float(np.hypot(p[0], p[1])), 1e-9)
        easy = radial * outward_weight + np.array([0.0, 0.0, -1.0])
        keys.append((-round(float(g.score), 9), -float(a @ easy), r))
    return [k[2] for k in sorted(keys)]


def grasp_key(grasp: Any, config: OrderingConfig = OrderingConfig()) -> tuple:
    """The same physical grasp gives the same key: P_G to ``same_position_m`` (1 mm), approach
    axis to ``same_axis`` (0.01: ~0.6 deg), and the closing axis up to its sign."""
    closing = np.asarray(grasp.rotation)[:, 0]
    closing = closing if (closing[np.argmax(np.abs(closing))] > 0) else -closing
    return (
        tuple(np.round(np.asarray(grasp.position) / config.same_position_m).astype(int)),
        tuple(np.round(np.asarray(grasp.rotation)[:, 2] / config.same_axis).astype(int)),
        tuple(np.round(closing / config.same_axis).astype(int)),
    )


def distinct_in_order(
    grasps: Sequence[Any], max_ranks: int, config: OrderingConfig = OrderingConfig()
) -> list[int]:
    """The ranks tried, in order: :func:`execution_order` over ``max_ranks * tie_window``
    grasps, duplicates of an earlier one (planners emit twins) left out, at most ``max_ranks``."""
    out: list[int] = []
    seen: set[tuple] = set()
    window = max_ranks * config.tie_window
    for r in execution_order(grasps, window, config.easy_approach_outward):
        if len(out) >= max_ranks:
            break
        key = grasp_key(grasps[r], config)
        if key in seen:
            continue
        seen.add(key)
        out.append(r)
    return out
