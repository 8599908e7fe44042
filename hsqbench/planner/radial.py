"""Scaled radial distance to a superquadric and its Jacobian, for the EMS M-step.

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

The Jacobian of ``d`` is taken as ``cos(theta)`` times that of ``r`` (the Gauss-Newton
approximation: the neglected term ``r d cos(theta)`` vanishes at a zero residual); the optimiser
accepts a step only if the exact cost falls. The pose is updated on the right,
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


def _pair(u: Array, v: Array, t: float) -> tuple[Array, Array, Array, Array, Array]:
    """Power mean of a pair and its pieces: value, share of u, share of v, d ln(value) / d t."""
    u_hi = u >= v
    hi = np.where(u_hi, u, v)
    lo = np.where(u_hi, v, u)
    q = lo / np.where(hi > 0.0, hi, 1.0)
    qt = q ** (1.0 / t)
    one_qt = 1.0 + qt
    value = hi * one_qt**t
    s_lo = qt / one_qt
    s_hi = 1.0 - s_lo
    s_u = np.where(u_hi, s_hi, s_lo)
    s_v = np.where(u_hi, s_lo, s_hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        s_lo_log_q = np.where(s_lo > 0.0, s_lo * np.log(q), 0.0)
    dlog_dt = np.log(one_qt) - s_lo_log_q / t
    return value, s_u, s_v, dlog_dt, q


def radial_residual(
    points: Array, state: SQState, jacobian: bool = False
) -> tuple[Array, Array | None]:
    """Scaled signed radial distances ``d`` (N,), metres, and the (N, 11) Jacobian when asked."""
    local = (points - state.translation) @ state.rotation
    rho = np.sqrt(np.einsum("ij,ij->i", local, local))
    at_centre = rho < _RHO_MIN
    safe_rho = np.where(at_centre, 1.0, rho)
    n = local / safe_rho[:, None]
    n[at_centre] = (0.0, 0.0, 1.0)
    u = (n / state.scale) ** 2
    inner, s_x, s_y, dlnp_de2, _ = _pair(u[:, 0], u[:, 1], state.eps2)
    g, s_p, s_z, dlng_de1, _ = _pair(inner, u[:, 2], state.eps1)
    rad = 1.0 / np.sqrt(g)
    r = rho - rad
    c = np.column_stack([s_p * s_x, s_p * s_y, s_z])
    with np.errstate(divide="ignore", invalid="ignore"):
        c_over_n = np.where(n != 0.0, c / n, 0.0)
    cos = 1.0 / np.sqrt(np.einsum("ij,ij->i", c_over_n, c_over_n))
    if not jacobian:
        return r * cos, None
    half_rad = 0.5 * rad
    jac = np.empty((len(points), 11))
    jac[:, 0] = half_rad * dlng_de1
    jac[:, 1] = half_rad * s_p * dlnp_de2
    jac[:, 2:5] = -rad[:, None] * c
    grad = n - (rad / safe_rho)[:, None] * (n - c_over_n)
    grad[at_centre] = 0.0
    jac[:, 5:8] = np.cross(grad, local)
    jac[:, 8:11] = -grad
    jac *= cos[:, None]
    return r * cos, jac


def apply_increment(
    state: SQState,
    delta: Array,
    eps_bounds: tuple[float, float],
    scale_bounds: tuple[float, float],
) -> SQState:
    """State after the local increment ``delta`` (column order of :func:`radial_residual`), clipped."""
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
