"""Cloud points in the frame of each closing line, computed in chunks of lines.

Shared by the support and collision rules of :mod:`hsqbench.planner.hsq.stage_two.elimination`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

#: Line-by-point pairs processed at once: a dozen float32 arrays of this size stay in cache.
_CHUNK_PAIRS = 100_000


def _line_coordinates(
    points: NDArray,
    centres: NDArray,
    directions: NDArray,
    approach0: NDArray,
    lines_first: bool = False,
) -> tuple[NDArray, NDArray, NDArray]:
    """Points in each line's frame: ``s`` along ``d``, ``u`` along ``e1``, ``v`` along ``e2``; (M, L),
    or (L, M) with ``lines_first``.

    float32, relative to each line's centre (so a few micrometres at most are lost, far below
    the cloud's noise) and half the memory traffic of float64. Written as broadcast sums, not
    ``points @ axes.T``: a (M, 3) x (3, L) product is too skinny for BLAS, whose threads only
    add overhead on a busy machine.
    """
    e2 = np.cross(directions, approach0)
    rel = [points[:, k].astype(np.float32) for k in range(3)]

    def project(axes: NDArray) -> NDArray:
        # Summed as (L, M), whose rows are long: an (M, L) broadcast walks rows of only L (a few
        # dozen) elements, at twice the cost. Same sums, same order.
        offset = np.einsum("ij,ij->i", centres, axes).astype(np.float32)
        a = axes.T.astype(np.float32)[:, :, None]
        out = rel[0] * a[0]
        out += rel[1] * a[1]
        out += rel[2] * a[2]
        out -= offset[:, None]
        return out if lines_first else np.ascontiguousarray(out.T)

    return project(directions), project(approach0), project(e2)


def _chunks(n_lines: int, n_points: int):
    size = max(1, _CHUNK_PAIRS // max(n_points, 1))
    for start in range(0, n_lines, size):
        yield slice(start, min(start + size, n_lines))
