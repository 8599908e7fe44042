"""Overflow-free primitives of the superquadric inside-outside function (nested lp norms).

See :mod:`hsqbench.superquadric` for the formulas: ``phi`` evaluates ``(u^(1/t) + v^(1/t))^t`` as
``max * (1 + (min/max)^(1/t))^t`` so that no power of a small eps overflows.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Shape exponents are kept within these bounds everywhere (dimensionless).
EPS_MIN = 0.05
EPS_MAX = 2.0
#: Vertices per quarter curve of the fine polylines used to reparametrise superellipses by arc length;
#: 1024 keeps chord errors far below any sampling spacing, even for eps = 0.05 corners.
_CURVE_FINE = 1024


def _phi(u: NDArray, v: NDArray, t: float | NDArray) -> NDArray:
    """``(u^(1/t) + v^(1/t))^t`` for u, v >= 0 without overflow or underflow."""
    hi = np.maximum(u, v)
    lo = np.minimum(u, v)
    safe_hi = np.where(hi > 0.0, hi, 1.0)
    ratio = lo / safe_hi
    out = hi * (1.0 + ratio ** (1.0 / t)) ** t
    return np.where(hi > 0.0, out, 0.0)


def _phi_ratios(u: NDArray, v: NDArray, t: float | NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """``phi(u, v, t)`` with the ratios ``u / phi`` and ``v / phi`` (in [0, 1]; 0 where phi = 0)."""
    hi = np.maximum(u, v)
    lo = np.minimum(u, v)
    pos = hi > 0.0
    rho = lo / np.where(pos, hi, 1.0)
    r_hi = np.where(pos, (1.0 + rho ** (1.0 / t)) ** (-t), 0.0)
    r_lo = rho * r_hi
    value = np.where(pos, hi / np.where(pos, r_hi, 1.0), 0.0)
    u_is_hi = u >= v
    return value, np.where(u_is_hi, r_hi, r_lo), np.where(u_is_hi, r_lo, r_hi)


def _quarter_curve(eps: float, a: float, b: float) -> tuple[NDArray, NDArray, NDArray]:
    """Fine polyline of the quarter superellipse ``(c/a)^(2/eps) + (h/b)^(2/eps) = 1``.

    Runs from ``(0, b)`` to ``(a, 0)``; returns ``c`` (increasing), ``h`` and the arc length from
    ``(0, b)``, metres. Vertices are spread by the polar angle, which resolves both the flat parts
    and the rounded corners of small-eps curves.
    """
    theta = np.linspace(0.5 * np.pi, 0.0, _CURVE_FINE)
    cos, sin = np.cos(theta), np.sin(theta)
    cos[0], sin[-1] = 0.0, 0.0
    radius = 1.0 / np.sqrt(_phi((cos / a) ** 2, (sin / b) ** 2, eps))
    c, h = radius * cos, radius * sin
    length = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(c), np.diff(h)))])
    return c, h, length


def as_points(points: ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Validate and return an (N, 3) float64 array."""
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == 3:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    return arr


class SurfaceShape(Protocol):
    """What the sampling and mesh helpers read of a superquadric: shape, pose and the
    inside-outside function. :class:`~hsqbench.superquadric.geometry.Superquadric` calls those
    helpers, so they name this interface rather than the class: imports go one way."""

    eps1: float
    eps2: float
    scale: NDArray[np.float64]
    rotation: NDArray[np.float64]

    def inside_outside_pow(self, points: ArrayLike, local: bool = False) -> NDArray[np.float64]: ...

    def to_world(self, points: ArrayLike) -> NDArray[np.float64]: ...

    def _rho_gradient(self, local: NDArray) -> NDArray[np.float64]: ...
