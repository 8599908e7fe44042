"""Watertight triangle mesh of a superquadric (spherical product of two superellipses)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from hsqbench.superquadric.primitives import SurfaceShape, _quarter_curve


def _surface_mesh(
    sq: SurfaceShape, n_quarter: int
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """:meth:`Superquadric.to_mesh` (documented there): rings of equal arc-length steps, two poles."""
    n = int(n_quarter)
    if n < 2:
        raise ValueError(f"n_quarter must be >= 2, got {n_quarter}")
    ax, ay, az = sq.scale

    def quarter(eps: float, a: float, b: float) -> tuple[NDArray, NDArray]:
        """n + 1 points from (a, 0) to (0, b), normalised by (a, b), equal arc-length steps."""
        c, h, length = _quarter_curve(eps, a, b)
        steps = np.linspace(length[-1], 0.0, n + 1)
        return np.interp(steps, length, c) / a, np.interp(steps, length, h) / b

    cx, cy = quarter(sq.eps2, ax, ay)
    ring = np.concatenate(
        [
            np.column_stack([cx[:n], cy[:n]]),
            np.column_stack([-cx[n:0:-1], cy[n:0:-1]]),
            np.column_stack([-cx[:n], -cy[:n]]),
            np.column_stack([cx[n:0:-1], -cy[n:0:-1]]),
        ]
    )
    mc, mh = quarter(sq.eps1, 0.5 * (ax + ay), az)  # from the equator to the north pole
    lat_c = np.concatenate([mc[n - 1 : 0 : -1], mc[0:1], mc[1:n]])
    lat_h = np.concatenate([mh[n - 1 : 0 : -1], mh[0:1], -mh[1:n]])
    n_ring = ring.shape[0]
    rings = np.column_stack(
        [
            np.outer(lat_c, ring[:, 0]).ravel(),
            np.outer(lat_c, ring[:, 1]).ravel(),
            np.repeat(lat_h, n_ring),
        ]
    )
    local = np.vstack([rings, [[0.0, 0.0, 1.0]], [[0.0, 0.0, -1.0]]]) * sq.scale
    local /= np.sqrt(sq.inside_outside_pow(local, local=True))[:, None]

    n_lat = lat_c.size
    north, south = n_lat * n_ring, n_lat * n_ring + 1
    k = np.arange(n_ring)
    k1 = (k + 1) % n_ring
    upper = (np.arange(n_lat - 1)[:, None] * n_ring + k).ravel()
    upper1 = (np.arange(n_lat - 1)[:, None] * n_ring + k1).ravel()
    lower, lower1 = upper + n_ring, upper1 + n_ring
    last = (n_lat - 1) * n_ring
    faces = np.concatenate(
        [
            np.column_stack([np.full(n_ring, north), k, k1]),
            np.column_stack([upper, lower, lower1]),
            np.column_stack([upper, lower1, upper1]),
            np.column_stack([np.full(n_ring, south), last + k1, last + k]),
        ]
    )
    return sq.to_world(local), faces.astype(np.int64)
