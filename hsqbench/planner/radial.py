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

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hsqbench.superquadric import Superquadric

Array = NDArray[np.float64]

#: Radius below which a point counts as the centre (m): the ray direction is undefined there.
_RHO_MIN = 1e-12


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
    """``phi(u, v, t)``, the shares of u and v, and ``(ln q, ln(1 + q^(1/t)), s_lo)`` for d/dt."""
    hi = np.maximum(np.maximum(u, v), 1e-300)
    lo = np.minimum(u, v)
    with np.errstate(divide="ignore"):
        log_q = np.log(lo / hi)
    qt = np.exp(log_q / t)
    log_1qt = np.log1p(qt)
    value = hi * np.exp(t * log_1qt)
    s_lo = qt / (1.0 + qt)
    u_hi = u >= v
    s_u = np.where(u_hi, 1.0 - s_lo, s_lo)
    return value, s_u, 1.0 - s_u, (log_q, log_1qt, s_lo)


def _dlog_dt(pieces: tuple[Array, Array, Array], t: float) -> Array:
    """``d ln phi / d t = ln(1 + q^(1/t)) - s_lo ln(q) / t`` (0 * ln 0 taken as 0)."""
    log_q, log_1qt, s_lo = pieces
    s_log_q = np.where(s_lo > 0.0, s_lo * np.where(s_lo > 0.0, log_q, 0.0), 0.0)
    return log_1qt - s_log_q / t


def evaluate(points_t: Array, state: SQState) -> Evaluation:
    """Scaled signed radial distances ``d`` (N,), metres, of the points ``points_t`` (3, N)."""
    local = state.rotation.T @ (points_t - state.translation[:, None])
    rho = np.sqrt(np.einsum("ij,ij->j", local, local))
    at_centre = rho < _RHO_MIN
    n = local / np.where(at_centre, 1.0, rho)
    if at_centre.any():
        n[:, at_centre] = ((0.0,), (0.0,), (1.0,))
    u = (n / state.scale[:, None]) ** 2
    inner, s_x, s_y, inner_pieces = _pair(u[0], u[1], state.eps2)
    g, s_p, s_z, outer_pieces = _pair(inner, u[2], state.eps1)
    rad = 1.0 / np.sqrt(g)
    c = np.stack([s_p * s_x, s_p * s_y, s_z])
    c_over_n = np.divide(c, n, out=np.zeros_like(c), where=n != 0.0)
    cos = 1.0 / np.sqrt(np.einsum("ij,ij->j", c_over_n, c_over_n))
    r = rho - rad
    return Evaluation(
        d=r * cos,
        r=r,
        local=local,
        n=n,
        rho=np.where(at_centre, 0.0, rho),
        rad=rad,
        c=c,
        c_over_n=c_over_n,
        cos=cos,
        inner=(*inner_pieces[:2], inner_pieces[2]),
        outer=outer_pieces,
        eps1=state.eps1,
        eps2=state.eps2,
    )


def jacobian(ev: Evaluation, rows: NDArray[np.int64] | None = None) -> Array:
    """The (11, M) Jacobian of the radial distance ``r`` at the points ``rows`` (all when None)."""
    sel = slice(None) if rows is None else rows
    rad, rho = ev.rad[sel], ev.rho[sel]
    n, c, c_over_n, local = ev.n[:, sel], ev.c[:, sel], ev.c_over_n[:, sel], ev.local[:, sel]
    inner = tuple(a[sel] for a in ev.inner)
    outer = tuple(a[sel] for a in ev.outer)
    s_p = c[0] + c[1]
    half = 0.5 * rad
    jac = np.empty((11, rad.size))
    jac[0] = half * _dlog_dt(outer, ev.eps1)
    jac[1] = half * s_p * _dlog_dt(inner, ev.eps2)
    jac[2:5] = -rad * c
    safe_rho = np.where(rho > 0.0, rho, np.inf)
    grad = n - (rad / safe_rho) * (n - c_over_n)
    jac[5:8] = np.cross(grad, local, axis=0)
    jac[8:11] = -grad
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
    angle = float(np.linalg.norm(w))
    if angle > 0.0:
        k = w / angle
        kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        step = np.eye(3) + np.sin(angle) * kx + (1.0 - np.cos(angle)) * (kx @ kx)
        rotation = state.rotation @ step
    else:
        rotation = state.rotation
    return SQState(
        float(np.clip(state.eps1 + delta[0], *eps_bounds)),
        float(np.clip(state.eps2 + delta[1], *eps_bounds)),
        np.clip(state.scale * np.exp(delta[2:5]), *scale_bounds),
        rotation,
        state.translation + state.rotation @ delta[8:11],
    )
