"""Grasp ordering and de-duplication: pure functions on a planner's grasps (anything with
``position`` (3,), ``rotation`` (3, 3) and ``score``)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

#: Grasps looked at per rank tried when ordering ties (see :func:`execution_order`).
TIE_WINDOW = 8
#: Weight of "away from the robot" against "down" in the easy approach direction.
EASY_APPROACH_OUTWARD = 0.4


def execution_order(grasps: Sequence[Any], window: int) -> list[int]:
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
        easy = radial * EASY_APPROACH_OUTWARD + np.array([0.0, 0.0, -1.0])
        keys.append((-round(float(g.score), 9), -float(a @ easy), r))
    return [k[2] for k in sorted(keys)]


def grasp_key(grasp: Any) -> tuple:
    """The same physical grasp gives the same key: P_G to 1 mm, approach axis to ~0.6 deg, and
    the closing axis up to its sign."""
    closing = np.asarray(grasp.rotation)[:, 0]
    closing = closing if (closing[np.argmax(np.abs(closing))] > 0) else -closing
    return (
        tuple(np.round(np.asarray(grasp.position) / 0.001).astype(int)),
        tuple(np.round(np.asarray(grasp.rotation)[:, 2] / 0.01).astype(int)),
        tuple(np.round(closing / 0.01).astype(int)),
    )


def distinct_in_order(grasps: Sequence[Any], max_ranks: int) -> list[int]:
    """The ranks tried, in order: :func:`execution_order` over ``max_ranks * TIE_WINDOW``
    grasps, duplicates of an earlier one (planners emit twins) left out, at most ``max_ranks``."""
    out: list[int] = []
    seen: set[tuple] = set()
    for r in execution_order(grasps, max_ranks * TIE_WINDOW):
        if len(out) >= max_ranks:
            break
        key = grasp_key(grasps[r])
        if key in seen:
            continue
        seen.add(key)
        out.append(r)
    return out
