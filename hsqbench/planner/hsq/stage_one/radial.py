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

from hsqbench.superquadric.geometry import Superquadric

Array = NDArray[np.float64]

#: Radius below which a point counts as the centre (m): the ray direction is undefined there.
_RHO_MIN = 1e-12
#: Floor of ratios before a logarithm.
_TINY = 1e-300
_EYE3 = np.eye(3)


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
class PartialEvaluation:
    """The signed radial distance ``r`` at a state, with the intermediate results that
    :func:`complete` turns into the rest of an :class:`Evaluation`: an LM trial that fails
    needs only ``r``.

    ``u`` holds the squared scaled direction ``(n_k / a_k)²`` (3, N), ``inner`` the inner power
    mean P, and each ``*_parts`` the ``(ln q, ln(1 + q^(1/t)), q^(1/t))`` of its pair.
    """

    r: Array
    local: Array  # (5, N): rows x y z, then x y again once :func:`jacobian` has run
    n: Array
    rho: Array
    rad: Array
    u: Array
    inner: Array
    inner_parts: tuple[Array, Array, Array]
    outer_parts: tuple[Array, Array, Array]
    eps1: float
    eps2: float


@dataclass
class Evaluation:
    """Scaled radial distances at a state, with what the Jacobian needs (all (3, N) or (N,)).

    Points are held transposed, (3, N), so that each coordinate is a contiguous row.
    """

    d: Array
    r: Array
    local: Array  # as in PartialEvaluation
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


# At the fits' 1500 points the cost is per array operation more than per element, so the
# functions below work in place on few buffers.


def _power_mean(
    u: Array, v: Array, t: float, hi_positive: bool = False
) -> tuple[Array, tuple[Array, Array, Array]]:
    """``phi(u, v, t)`` and ``(ln q, ln(1 + q^(1/t)), q^(1/t))``, ``q = lo / hi`` of the pair.

    ``q`` is floored at 1e-300, so ``ln q`` stays finite and ``q^(1/t)`` underflows to a share
    of zero where the smaller term vanishes. ``hi_positive``: the caller knows that the larger
    term is at least 1e-300, so the floor on the divisor, a no-op then, is skipped.
    """
    hi = np.maximum(u, v)
    log_q = np.minimum(u, v)
    log_q /= hi if hi_positive else np.maximum(hi, _TINY)
    np.log(np.maximum(log_q, _TINY, out=log_q), out=log_q)
    qt = log_q * (1.0 / t)
    np.exp(qt, out=qt)
    log_1qt = np.log1p(qt)
    value = np.exp(log_1qt * t)
    value *= hi
    return value, (log_q, log_1qt, qt)


def _shares(
    u: Array, v: Array, parts: tuple[Array, Array, Array], out_v: Array | None = None
) -> tuple[Array, Array, tuple[Array, Array, Array]]:
    """The shares of u and v in their power mean (that of v written to ``out_v`` if given),
    and ``(ln q, ln(1 + q^(1/t)), s_lo)`` for :func:`_dlog_dt`."""
    log_q, log_1qt, qt = parts
    s_lo = qt + 1.0
    np.divide(qt, s_lo, out=s_lo)
    s_u = np.where(u >= v, 1.0 - s_lo, s_lo)
    return s_u, np.subtract(1.0, s_u, out=out_v), (log_q, log_1qt, s_lo)


def _dlog_dt(pieces: tuple[Array, Array, Array], t: float, out: Array) -> Array:
    """``d ln phi / d t = ln(1 + q^(1/t)) - s_lo ln(q) / t``, written to ``out``."""
    log_q, log_1qt, s_lo = pieces
    np.multiply(s_lo, log_q, out=out)
    out *= 1.0 / t
    return np.subtract(log_1qt, out, out=out)


def partial_evaluate(points_t: Array, state: SQState) -> PartialEvaluation:
    """Signed radial distances ``r`` (N,), metres, of the points ``points_t`` (3, N)."""
    # rows x y z x y: the Jacobian's cross product needs x and y repeated (filled there)
    local5 = np.empty((5, points_t.shape[1]))
    local = np.matmul(state.rotation.T, points_t - state.translation[:, None], out=local5[:3])
    rho = np.sqrt(np.einsum("ij,ij->j", local, local))
    rho_min = rho.min()
    n = local / (rho if rho_min >= _RHO_MIN else np.maximum(rho, _RHO_MIN))
    if rho_min < _RHO_MIN:  # the centre itself: any direction will do
        n[:, rho < _RHO_MIN] = ((0.0,), (0.0,), (1.0,))
        rho = np.where(rho < _RHO_MIN, 0.0, rho)
    u = n / state.scale[:, None]
    u *= u
    inner, inner_parts = _power_mean(u[0], u[1], state.eps2)
    # inner >= max(u[0], u[1]) and n is a unit vector, so max(inner, u[2]) >= 1 / (3 a_max²),
    # far above the floor of _power_mean
    g, outer_parts = _power_mean(inner, u[2], state.eps1, hi_positive=True)
    rad = np.divide(1.0, np.sqrt(g, out=g), out=g)
    return PartialEvaluation(
        rho - rad, local5, n, rho, rad, u, inner, inner_parts, outer_parts, state.eps1, state.eps2
    )


def complete(part: PartialEvaluation) -> Evaluation:
    """The full :class:`Evaluation` of a :class:`PartialEvaluation`."""
    u, n = part.u, part.n
    c = np.empty_like(u)
    s_x, s_y, inner_pieces = _shares(u[0], u[1], part.inner_parts)
    s_p, _, outer_pieces = _shares(part.inner, u[2], part.outer_parts, out_v=c[2])
    np.multiply(s_p, s_x, out=c[0])
    np.multiply(s_p, s_y, out=c[1])
    # c / n with c / 0 read as 0 (an axis the ray does not move along adds no slope)
    c_over_n = c / n if n.all() else c / np.where(n != 0.0, n, np.inf)
    cos = np.einsum("ij,ij->j", c_over_n, c_over_n)
    np.divide(1.0, np.sqrt(cos, out=cos), out=cos)
    return Evaluation(
        d=part.r * cos,
        r=part.r,
        local=part.local,
        n=n,
        rho=part.rho,
        rad=part.rad,
        c=c,
        c_over_n=c_over_n,
        cos=cos,
        inner=inner_pieces,
        outer=outer_pieces,
        eps1=part.eps1,
        eps2=part.eps2,
    )


def evaluate(points_t: Array, state: SQState) -> Evaluation:
    """Scaled signed radial distances ``d`` (N,), metres, of the points ``points_t`` (3, N)."""
    return complete(partial_evaluate(points_t, state))


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
    np.multiply(_dlog_dt(outer, ev.eps1, jac[0]), half, out=jac[0])
    slope = c[0] + c[1]
    slope *= half
    np.multiply(_dlog_dt(inner, ev.eps2, jac[1]), slope, out=jac[1])
    np.multiply(-rad, c, out=jac[2:5])
    # grad = n - (rad / rho) (n - c / n), with rad / 0 read as 0 at the centre; rows x y z x y,
    # so that grad x local is three whole-array operations on shifted rows
    grad = np.empty((5, rad.size))
    np.subtract(n, c_over_n, out=grad[:3])
    grad[:3] *= rad / rho if rho.min() > 0.0 else rad / np.where(rho > 0.0, rho, np.inf)
    np.subtract(n, grad[:3], out=grad[:3])
    grad[3:] = grad[:2]
    local[3:] = local[:2]
    np.multiply(grad[1:4], local[2:5], out=jac[5:8])
    jac[5:8] -= grad[2:5] * local[1:4]
    np.negative(grad[:3], out=jac[8:11])
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
    if angle > 0.0:  # Rodrigues' formula; k from Python floats, which numpy reads quicker
        kx, ky, kz = (w / angle).tolist()
        k = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
        rotation = rotation @ (_EYE3 + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k))
    lo, hi = eps_bounds
    return SQState(
        min(max(state.eps1 + float(delta[0]), lo), hi),
        min(max(state.eps2 + float(delta[1]), lo), hi),
        np.minimum(np.maximum(state.scale * np.exp(delta[2:5]), scale_bounds[0]), scale_bounds[1]),
        rotation,
        state.translation + state.rotation @ delta[8:11],
    )
