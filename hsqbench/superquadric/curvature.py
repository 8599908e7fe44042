"""Analytic Gaussian curvature of superquadric surfaces, vectorised over many superquadrics."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.superquadric.primitives import EPS_MAX, EPS_MIN, _phi, _phi_ratios, as_points

#: Curvature is evaluated at least this far (in units of the semi-axes) from the planes of the local
#: axes. For eps > 1 the curvature at an axis endpoint is unbounded, so the value there is the one
#: 1e-4 semi-axes away: large but finite (1e5 to 2e8 1/m^2 for eps1 = eps2 in [1.2, 1.99] and
#: semi-axes of 1.5-5 cm; the rest of such surfaces is below about 1e4).
CURVATURE_AXIS_OFFSET = 1e-4


def gaussian_curvature_local(
    local: ArrayLike, eps1: ArrayLike, eps2: ArrayLike, scale: ArrayLike
) -> NDArray[np.float64]:
    """Gaussian curvature (1/m^2) of superquadric surfaces at local-frame points, row by row.

    ``eps1``, ``eps2`` are scalars or (N,) and ``scale`` is (3,) or (N, 3), so one call can serve
    many superquadrics. Each point is first projected radially onto its surface; points within
    :data:`CURVATURE_AXIS_OFFSET` semi-axes of an axis plane are moved to that distance (the
    curvature is unbounded at the axis endpoints when eps > 1). The centre maps to the +z tip.

    Math: in scaled coordinates ``q = p / scale`` the surface is ``rho(q) = 1`` with the nested lp
    norm ``rho = ||(m, qz)||_p1``, ``m = ||(qx, qy)||_p2``, ``p = 2 / eps`` (rho = 1 after the
    projection, so it drops out of the code). With ``a2 = |qx|/m``,
    ``b2 = |qy|/m``, ``a1 = m/rho``, ``b1 = |qz|/rho`` the Hessian of rho has rank 2,
    ``Hq = c1 u u^T + c2 w w^T`` with

        u = (b1 a2^(p2-1) sx, b1 b2^(p2-1) sy, -a1 sz),   c1 = (p1-1)/rho (a1 b1)^(p1-2),
        w = (b2 sx, -a2 sy, 0),                           c2 = (p2-1)/rho a1^(p1-2) (a2 b2)^(p2-2),

    so ``adj(Hq) = c1 c2 (u x w)(u x w)^T`` and, with the gradient ``gq`` and ``D = diag(scale)``,
    ``K = g^T adj(H) g / |g|^4 = c1 c2 det[gq, u, w]^2 / (det(D)^2 |D^-1 gq|^4)``. Every factor is
    a ratio in [0, 1] to a power that is non-negative, or at least -1 with the ratio floored by the
    axis offset, so K is finite and >= 0 (superquadrics with eps <= 2 are convex).
    """
    local = as_points(local)
    scale = np.broadcast_to(np.asarray(scale, dtype=np.float64), local.shape)
    if not (np.all(scale > 0.0) and np.all(np.isfinite(scale)) and np.all(np.isfinite(local))):
        raise ValueError("points must be finite and scales finite and positive (metres)")
    q = local / scale
    e1 = np.broadcast_to(np.asarray(eps1, dtype=np.float64), q.shape[:1])
    e2 = np.broadcast_to(np.asarray(eps2, dtype=np.float64), q.shape[:1])
    eps = np.concatenate([e1, e2])
    if not np.all((eps >= EPS_MIN - 1e-9) & (eps <= EPS_MAX + 1e-9)):
        raise ValueError(f"eps1, eps2 must lie in [{EPS_MIN}, {EPS_MAX}]")

    def norm(q: NDArray) -> NDArray:
        return np.sqrt(_phi(_phi(q[:, 0] ** 2, q[:, 1] ** 2, e2), q[:, 2] ** 2, e1))

    rho = norm(q)
    q = np.where(rho[:, None] > 0.0, q / np.where(rho > 0.0, rho, 1.0)[:, None], (0.0, 0.0, 1.0))
    sign = np.where(q < 0.0, -1.0, 1.0)
    q = sign * np.maximum(np.abs(q), CURVATURE_AXIS_OFFSET)
    q /= norm(q)[:, None]

    sq = q**2
    h, r_x, r_y = _phi_ratios(sq[:, 0], sq[:, 1], e2)
    _, r_h, r_z = _phi_ratios(h, sq[:, 2], e1)
    a2, b2, a1, b1 = np.sqrt(r_x), np.sqrt(r_y), np.sqrt(r_h), np.sqrt(r_z)
    p1, p2 = np.maximum(2.0 / e1, 1.0), np.maximum(2.0 / e2, 1.0)  # eps may exceed 2 by rounding
    grad_m = sign[:, :2] * np.stack([a2 ** (p2 - 1.0), b2 ** (p2 - 1.0)], axis=1)
    grad = np.column_stack([(a1 ** (p1 - 1.0))[:, None] * grad_m, sign[:, 2] * b1 ** (p1 - 1.0)])
    u = np.column_stack([b1[:, None] * grad_m, -sign[:, 2] * a1])
    w = np.column_stack([b2 * sign[:, 0], -a2 * sign[:, 1], np.zeros_like(a2)])
    c1 = (p1 - 1.0) * (r_h * r_z) ** (0.5 * p1 - 1.0)
    c2 = (p2 - 1.0) * a1 ** (p1 - 2.0) * (r_x * r_y) ** (0.5 * p2 - 1.0)
    triple = np.einsum("ij,ij->i", grad, np.cross(u, w))
    det_d = np.prod(scale, axis=1)
    grad_p = np.sum((grad / scale) ** 2, axis=1)
    return c1 * c2 * triple**2 / (det_d**2 * grad_p**2)
