"""Colours of the episode viewer: a score colour map and one colour per rejection reason."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Viridis at 0, 1/4, 1/2, 3/4 and 1 (matplotlib's values): perceptually even, colour-blind safe;
#: a score of 0 is dark purple, 1 is yellow.
_VIRIDIS = np.array(
    [
        [68, 1, 84],
        [59, 82, 139],
        [33, 145, 140],
        [94, 201, 98],
        [253, 231, 37],
    ],
    dtype=np.float64,
)

#: Candidates removed by each elimination rule (``hsqbench.planner.hsq.stage_two.candidates.REJECTION_REASONS``).
REASON_COLORS: dict[str, tuple[int, int, int, int]] = {
    "duplicate": (90, 110, 160, 255),  # slate: the same line exists from a better superquadric
    "width": (150, 150, 150, 255),  # grey: never a possible grasp
    "support": (255, 140, 0, 255),  # orange: nothing under a finger
    "table": (140, 80, 30, 255),  # brown: the hand would enter the table
    "collision": (220, 30, 30, 255),  # red: the hand would hit the cloud
    "sweep": (170, 60, 200, 255),  # purple: the approach would sweep through the cloud
    "hidden": (230, 60, 160, 255),  # magenta: the hand would enter a body the cameras cannot see
}
#: A rejection reason without its own colour (a rule added after this table).
OTHER_REASON_COLOR = (60, 60, 60, 255)
#: Anything without a score (a superquadric with no surviving grasp).
NO_SCORE_COLOR = (120, 120, 120, 255)
#: The two cameras' points (left, right) and any further ones.
CAMERA_COLORS = np.array(
    [[31, 119, 180, 255], [214, 39, 40, 255], [44, 160, 44, 255], [148, 103, 189, 255]],
    dtype=np.uint8,
)


def score_colors(scores: ArrayLike, alpha: int = 255) -> NDArray[np.uint8]:
    """RGBA (N, 4) uint8 of scores in [0, 1] on viridis; NaN -> :data:`NO_SCORE_COLOR`.

    Scores outside [0, 1] are clipped (the hsq score is a product of factors in [0, 1]).
    """
    s = np.asarray(scores, dtype=np.float64).reshape(-1)
    finite = np.isfinite(s)
    x = np.clip(np.where(finite, s, 0.0), 0.0, 1.0) * (len(_VIRIDIS) - 1)
    lo = np.minimum(np.floor(x).astype(np.int64), len(_VIRIDIS) - 2)
    t = (x - lo)[:, None]
    rgb = (1.0 - t) * _VIRIDIS[lo] + t * _VIRIDIS[lo + 1]
    out = np.empty((s.size, 4), dtype=np.uint8)
    out[:, :3] = np.round(rgb).astype(np.uint8)
    out[:, 3] = alpha
    out[~finite] = NO_SCORE_COLOR
    return out


def camera_colors(camera_index: ArrayLike) -> NDArray[np.uint8]:
    """RGBA (N, 4) uint8 for each point's camera index (cycling over :data:`CAMERA_COLORS`)."""
    idx = np.asarray(camera_index, dtype=np.int64).reshape(-1)
    return CAMERA_COLORS[np.mod(idx, len(CAMERA_COLORS))]
