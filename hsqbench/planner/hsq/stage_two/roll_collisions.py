"""Exact point-in-gripper tests at every roll of each closing line (elimination rules 4 and 5).

In the frame of a line (``s`` along it, polar ``r, theta`` about it) a point is inside a box at
roll ``phi`` iff ``s`` is within the box's extent along the closing axis and ``psi = theta - phi``
satisfies ``r cos(psi) in [z_lo, z_hi]`` and ``|r sin(psi)| <= y_half``: at most four arcs of
``phi``, which mark the discrete rolls they contain. Cost O(lines x points), not O(candidates x
points).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.hsq.stage_two.candidates import CandidateSet
from hsqbench.planner.hsq.stage_two.line_frame import _chunks, _line_coordinates

#: Slack, in roll steps, when deciding whether a discrete roll lies in an arc (favours collision;
#: covers the float32 rounding of the angles, about 1e-7 rad).
_ARC_SLACK = 1e-5
#: An interval of |psi| that ends within this of 0 or pi (radians, float32 rounding) reaches it.
_ANGLE_TOL = 1e-6


def _mark_arcs(
    r: NDArray,
    theta: NDArray,
    line: NDArray[np.int64],
    box: NDArray,
    n_roll: int,
    diff: NDArray,
) -> None:
    """Add +1/-1 markers to ``diff`` (n_lines, 4 n_roll + 1; roll ``j`` at column ``j + 2
    n_roll``) for the rolls at which each point, at distance ``r`` and angle ``theta`` about its
    line and within ``box``'s extent along the line, lies inside ``box`` (grasp frame,
    symmetric in y).

    The point is inside at roll ``phi`` iff ``psi = theta - phi`` has ``r cos(psi)`` in
    ``[z_lo, z_hi]`` (``|psi|`` in ``[a_lo, a_hi]``) and ``|r sin(psi)| <= y_half`` (``|psi|``
    in ``[0, beta]`` or ``[pi - beta, pi]``): one or two intervals of ``|psi|``, each two arcs of
    ``phi`` that merge into one when the interval reaches 0 or pi.
    """
    # Python floats: they keep float32 arrays float32 (a numpy float64 scalar would not).
    z_lo, y_hi, z_hi = float(box[0, 2]), float(box[1, 1]), float(box[1, 2])
    rs = np.maximum(r, 1e-12)
    reach = (z_lo <= rs) & (z_hi >= -rs)
    a_lo = np.arccos(np.clip(z_hi / rs, -1.0, 1.0))
    a_hi = np.arccos(np.clip(z_lo / rs, -1.0, 1.0))
    beta = np.arcsin(np.clip(y_hi / rs, 0.0, 1.0))
    intervals = []
    if z_hi > 0.0:  # else a_lo > pi/2 >= beta: the first interval is empty
        intervals.append((a_lo, np.minimum(a_hi, beta)))
    if z_lo < 0.0:  # else a_hi < pi/2 <= pi - beta: the second is empty
        intervals.append((np.maximum(a_lo, np.pi - beta), a_hi))
    if len(intervals) == 2:
        # Intervals that meet (a point within y_half of the line at every angle) are one: the
        # rolls at their junction are then marked once, so the markers count points.
        (lo1, hi1), (lo2, hi2) = intervals
        meet = (lo1 <= hi1) & (lo2 <= hi2) & (hi1 >= lo2 - _ANGLE_TOL)
        intervals = [(lo1, np.where(meet, hi2, hi1)), (np.where(meet, np.inf, lo2), hi2)]
    step = 2.0 * np.pi / n_roll
    width = diff.shape[1]
    first, last = [], []
    for lo, hi in intervals:
        ok = reach & (lo <= hi)
        at_zero, at_pi = lo[ok] <= _ANGLE_TOL, hi[ok] >= np.pi - _ANGLE_TOL
        kinds = (at_zero & at_pi, at_zero & ~at_pi, ~at_zero & at_pi, ~at_zero & ~at_pi)
        for kind, use in enumerate(kinds):
            if not np.any(use):
                continue
            where = np.flatnonzero(ok)[use]
            t, p, q = theta[where], lo[where], hi[where]
            base = line[where] * width + 2 * n_roll
            # phi = theta - psi for psi in [p, q] and [-q, -p]; arcs that meet merge.
            if kind == 0:
                arcs = [(t - np.pi, t + np.pi)]
            elif kind == 1:
                arcs = [(t - q, t + q)]
            elif kind == 2:
                arcs = [(t + p - 2.0 * np.pi, t - p)]
            else:
                arcs = [(t - q, t - p), (t + p, t + q)]
            for start, stop in arcs:
                j_lo = np.ceil(start / step - _ARC_SLACK).astype(np.int64)
                j_hi = np.floor(stop / step + _ARC_SLACK).astype(np.int64)
                # A full circle ends where it starts: each roll once.
                j_hi = np.minimum(j_hi, j_lo + n_roll - 1)
                valid = j_lo <= j_hi
                first.append(base[valid] + j_lo[valid])
                last.append(base[valid] + j_hi[valid] + 1)
    if first:
        starts = np.bincount(np.concatenate(first), minlength=diff.size)
        stops = np.bincount(np.concatenate(last), minlength=diff.size)
        diff += (starts - stops).reshape(diff.shape)


def body_hits(
    points: NDArray,
    cands: CandidateSet,
    lines: NDArray[np.int64],
    boxes: NDArray,
    obstacle_radius: NDArray | None = None,
    obstacle_half_height: NDArray | None = None,
    max_points: int = 0,
) -> NDArray[np.bool_]:
    """(len(lines), R): whether more than ``max_points`` obstacle points lie inside each line's
    ``boxes``
    (n, k, 2, 3), grasp frame, at each roll.

    The boxes' extents across the closing axis (y, z) must be the same for every line and
    symmetric in y; their extents along it may differ (the fingers follow each line's opening).
    Obstacles are all ``points``, or, when ``obstacle_radius`` and ``obstacle_half_height`` (per
    line) are given, only the points with ``|s| <= half_height`` and ``r > radius`` (the paper's
    collision cylinder).
    """
    if not (
        np.allclose(boxes[:, :, :, 1:], boxes[:1, :, :, 1:])
        and np.allclose(boxes[:, :, 0, 1], -boxes[:, :, 1, 1])
    ):
        raise ValueError("box cross-sections must be shared by all lines and symmetric in y")
    n_roll = cands.n_roll
    out = np.zeros((lines.size, n_roll), dtype=bool)
    if lines.size == 0 or points.shape[0] == 0:
        return out
    L = cands.lines
    n_points = points.shape[0]
    for sl in _chunks(lines.size, n_points):
        idx = lines[sl]
        n = idx.size
        # (lines, points): the per-line bounds below broadcast along long rows; the markers
        # are integer counts, so the order in which points are met does not matter
        s, u, v = _line_coordinates(
            points, L.centres[idx], L.directions[idx], L.approach0[idx], lines_first=True
        )
        r2 = u * u + v * v
        obstacle = None
        if obstacle_radius is not None:
            obstacle = np.abs(s) <= obstacle_half_height[sl, None].astype(np.float32)
            obstacle &= r2 > (obstacle_radius[sl, None] ** 2).astype(np.float32)
        diff = np.zeros((n, 4 * n_roll + 1), dtype=np.int64)
        chunk_boxes = boxes[sl, :, :, :1].astype(np.float32)  # extents along the line
        for b in range(boxes.shape[1]):
            (_, _, z_lo), (_, y_hi, z_hi) = boxes[0, b]
            # The box's distance range from the line bounds r: a cheap filter before any
            # trigonometry.
            r_min = max(z_lo, -z_hi, 0.0)
            r_max2 = max(z_lo**2, z_hi**2) + y_hi**2
            mask = (s >= chunk_boxes[:, b, 0]) & (s <= chunk_boxes[:, b, 1])
            mask &= (r2 >= r_min * r_min) & (r2 <= r_max2)
            if obstacle is not None:
                mask &= obstacle
            flat = np.flatnonzero(mask)
            if flat.size == 0:
                continue
            r = np.sqrt(r2.flat[flat])
            theta = np.arctan2(v.flat[flat], u.flat[flat])
            _mark_arcs(r, theta, flat // n_points, boxes[0, b], n_roll, diff)
        # Points covering each roll (a point's arcs in one box are disjoint, the boxes too).
        inside = np.cumsum(diff, axis=1)[:, : 4 * n_roll].reshape(n, 4, n_roll).sum(axis=1)
        out[sl] = inside > max_points
    return out
