"""Scaled radial distance to a superquadric, and the Jacobian of the radial distance, for EMS.

For a point ``p`` in the superquadric's frame, ``rho = |p|`` and ``n = p / rho``, the surface along
the ray from the centre lies at radius ``Rad(n) = G(n)^(-1/2)`` (G = F^eps1 is homogeneous of
degree 2) and the signed radial distance is ``r = rho - Rad(n)`` (metres; > 0 outside).

The residual used is ``d = r cos(theta)``, theta the angle between the ray and the surface normal
where the ray crosses the surface: the distance from ``p`` to the tangent plane there, a first-order
Euclidean distance. The plain radial distance overstates the distance by ``1 / cos(theta)`` where
rays graze the surface, which pulls fits toward shapes whose centre sits far behind the visible
surface (measured: one-sided views of random superquadrics with 20 % outliers went from 75 % to 85 %
of fits within 4 mm, at equal cost on full views).

G is built from two stable power means ``phi(u, v, t) = (u^(1/t) + v^(1/t))^t``:

    P = phi(x²/ax², y²/ay², eps2),      G = phi(P, z²/az², eps1).

With the shares ``s_u = u^(1/t) / (u^(1/t) + v^(1/t))`` of each power mean (they sum to one) and
``c = (s_P s_x, s_P s_y, s_z)`` (the share of each axis in G, summing to one), the normal at the
crossing is parallel to ``c / n`` (elementwise), so ``cos(theta) = 1 / |c / n|``, and

    d lnG / d ln a_k   = -2 c_k
    d lnP / d eps2     = ln(1 + q^(1/eps2)) - s_lo ln(q) / eps2        (q = lo / hi of the pair)
    d lnG / d eps1     = same form for the outer pair,      d lnG / d eps2 = s_P d lnP / d eps2
    d r / d theta      = (Rad / 2) d lnG / d theta           for every shape parameter theta
    grad_p r           = n - (Rad / rho) (n - c / n)         (c / n elementwise).

:func:`jacobian` is the exact Jacobian of ``r``; the M-step (:mod:`.ems`) minimises
``sum w cos² r²`` with ``cos`` held at its value at the start of the step (reweighted least
squares), which equals ``sum w d²`` there. The pose is updated on the right,
``R <- R exp([w]x)`` and ``t <- t + R v``, so the columns of the local increments are
``d r / d w = grad_p r x p`` and ``d r / d v = -grad_p r``. Column order:
``eps1, eps2, ln ax, ln ay, ln az, w (3), v (3)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hsqbench.superquadric import Superquadric

Array = NDArray[np.float64]

#: Radius below which a point counts as the centre (m): the ray direction is undefined there.
_RHO_MIN = 1e-12
#: Floor of ratios before a logarithm.
_TINY = 1e-300


@dataclass
class SQState:
    """Superquadric parameters as the optimiser holds them (rotation as a matrix, metres)."""

    eps1: float
    eps2: float
    scale: Array
    rotation: Array
    translation: Array

    @classmethod
    def from_superquadric(cls, sq: Superquadric) -> SQState:
        return cls(sq.eps1, sq.eps2, sq.scale.copy(), sq.rotation.copy(), sq.translation.copy())

    def to_superquadric(self) -> Superquadric:
        return Superquadric(self.eps1, self.eps2, self.scale, self.rotation, self.translation)

    def copy(self) -> SQState:
        return SQState(
            self.eps1,
            self.eps2,
            self.scale.copy(),
            self.rotation.copy(),
            self.translation.copy(),
        )


@dataclass
class Evaluation:
    """Scaled radial distances at a state, with what the Jacobian needs (all (3, N) or (N,)).

    Points are held transposed, (3, N), so that each coordinate is a contiguous row.
    """

    d: Array
    r: Array
    local: Array
    n: Array
    rho: Array
    rad: Array
    c: Array
    c_over_n: Array
    cos: Array
    inner: tuple[Array, Array, Array]
    outer: tuple[Array, Array, Array]
    eps1: float
    eps2: float


def _pair(u: Array, v: Array, t: float) -> tuple[Array, Array, Array, tuple[Array, Array, Array]]:
    """``phi(u, v, t)``, the shares of u and v, and ``(ln q, ln(1 + q^(1/t)), s_lo)`` for d/dt.

    ``q = lo / hi`` is floored at 1e-300, so ``ln q`` stays finite and ``q^(1/t)`` underflows to
    a share of zero where the smaller term vanishes.
    """
    hi = np.maximum(u, v)
    log_q = np.log(np.maximum(np.minimum(u, v) / np.maximum(hi, _TINY), _TINY))
    qt = np.exp(log_q * (1.0 / t))
    log_1qt = np.log1p(qt)
    value = hi * np.exp(t * log_1qt)
    s_lo = qt / (1.0 + qt)
    s_u = np.where(u >= v, 1.0 - s_lo, s_lo)
    return value, s_u, 1.0 - s_u, (log_q, log_1qt, s_lo)


def _dlog_dt(pieces: tuple[Array, Array, Array], t: float) -> Array:
    """``d ln phi / d t = ln(1 + q^(1/t)) - s_lo ln(q) / t``."""
    log_q, log_1qt, s_lo = pieces
    return log_1qt - s_lo * log_q * (1.0 / t)


def evaluate(points_t: Array, state: SQState) -> Evaluation:
    """Scaled signed radial distances ``d`` (N,), metres, of the points ``points_t`` (3, N)."""
    local = state.rotation.T @ (points_t - state.translation[:, None])
    rho = np.sqrt(np.einsum("ij,ij->j", local, local))
    n = local / np.maximum(rho, _RHO_MIN)
    if rho.min() < _RHO_MIN:  # the centre itself: any direction will do
        n[:, rho < _RHO_MIN] = ((0.0,), (0.0,), (1.0,))
        rho = np.where(rho < _RHO_MIN, 0.0, rho)
    u = n / state.scale[:, None]
    u *= u
    inner, s_x, s_y, inner_pieces = _pair(u[0], u[1], state.eps2)
    g, s_p, s_z, outer_pieces = _pair(inner, u[2], state.eps1)
    rad = 1.0 / np.sqrt(g)
    c = np.empty_like(u)
    np.multiply(s_p, s_x, out=c[0])
    np.multiply(s_p, s_y, out=c[1])
    c[2] = s_z
    c_over_n = c / np.where(n != 0.0, n, np.inf)
    cos = 1.0 / np.sqrt(np.einsum("ij,ij->j", c_over_n, c_over_n))
    r = rho - rad
    return Evaluation(
        d=r * cos,
        r=r,
        local=local,
        n=n,
        rho=rho,
        rad=rad,
        c=c,
        c_over_n=c_over_n,
        cos=cos,
        inner=inner_pieces,
        outer=outer_pieces,
        eps1=state.eps1,
        eps2=state.eps2,
    )


def jacobian(ev: Evaluation, rows: NDArray[np.int64] | None = None) -> Array:
    """The (11, M) Jacobian of the radial distance ``r`` at the points ``rows`` (all when None)."""
    if rows is None:
        rad, rho, n, c, c_over_n, local = ev.rad, ev.rho, ev.n, ev.c, ev.c_over_n, ev.local
        inner, outer = ev.inner, ev.outer
    else:
        rad, rho, n = ev.rad[rows], ev.rho[rows], ev.n[:, rows]
        c, c_over_n, local = ev.c[:, rows], ev.c_over_n[:, rows], ev.local[:, rows]
        inner = tuple(a[rows] for a in ev.inner)
        outer = tuple(a[rows] for a in ev.outer)
    half = 0.5 * rad
    jac = np.empty((11, rad.size))
    np.multiply(half, _dlog_dt(outer, ev.eps1), out=jac[0])
    np.multiply(half * (c[0] + c[1]), _dlog_dt(inner, ev.eps2), out=jac[1])
    np.multiply(-rad, c, out=jac[2:5])
    grad = n - (rad / np.where(rho > 0.0, rho, np.inf)) * (n - c_over_n)
    # grad x local, row by row
    jac[5] = grad[1] * local[2] - grad[2] * local[1]
    jac[6] = grad[2] * local[0] - grad[0] * local[2]
    jac[7] = grad[0] * local[1] - grad[1] * local[0]
    np.negative(grad, out=jac[8:11])
    return jac


def radial_residual(points: Array, state: SQState) -> tuple[Array, Array]:
    """Scaled and plain signed radial distances ``(d, r)`` (N,) of points (N, 3), metres."""
    ev = evaluate(np.ascontiguousarray(points.T), state)
    return ev.d, ev.r


def apply_increment(
    state: SQState,
    delta: Array,
    eps_bounds: tuple[float, float],
    scale_bounds: tuple[float, float],
) -> SQState:
    """State after the local increment ``delta`` (column order of :func:`jacobian`), clipped."""
    w = delta[5:8]
    angle = math.sqrt(float(w @ w))
    rotation = state.rotation
    if angle > 0.0:
        kx, ky, kz = w / angle
        k = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
        rotation = rotation @ (np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k))
    lo, hi = eps_bounds
    return SQState(
        min(max(state.eps1 + float(delta[0]), lo), hi),
        min(max(state.eps2 + float(delta[1]), lo), hi),
        np.minimum(np.maximum(state.scale * np.exp(delta[2:5]), scale_bounds[0]), scale_bounds[1]),
        rotation,
        state.translation + state.rotation @ delta[8:11],
    )
