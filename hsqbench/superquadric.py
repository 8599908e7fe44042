"""Superquadric geometry, vectorised and numerically stable.

A superquadric in its own frame is the surface ``F(p) = 1`` of the inside-outside function

    F(x, y, z) = ((|x|/ax)^(2/eps2) + (|y|/ay)^(2/eps2))^(eps2/eps1) + (|z|/az)^(2/eps1)

with shape exponents ``eps1`` (along z) and ``eps2`` (in the xy cross-section), dimensionless, and
semi-axis scales ``ax, ay, az`` in metres. A pose ``(R, t)`` maps local to world: ``p_w = R p + t``.

Powers like ``u^(1/eps)`` overflow for small eps, so F is evaluated through

    phi(u, v, t) = max(u, v) * (1 + (min(u, v) / max(u, v))^(1/t))^t,

which gives ``G = F^eps1 = phi(phi(x²/ax², y²/ay², eps2), z²/az², eps1)`` without any large
intermediate. G is homogeneous of degree 2 in p, so the surface radius along a direction n is
``1 / sqrt(G(n))`` and the radial distance is ``| |p| - |p| / sqrt(G(p)) |``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

#: Shape exponents are kept within these bounds everywhere (dimensionless).
EPS_MIN = 0.05
EPS_MAX = 2.0
#: Largest finite F returned; beyond this a point is "infinitely" outside.
_LOG_F_MAX = 700.0

#: Length of the flat parameter vector: eps1, eps2, ax, ay, az, rotation vector (3), translation (3).
N_PARAMS = 11


def _phi(u: NDArray, v: NDArray, t: float | NDArray) -> NDArray:
    """``(u^(1/t) + v^(1/t))^t`` for u, v >= 0 without overflow or underflow."""
    hi = np.maximum(u, v)
    lo = np.minimum(u, v)
    safe_hi = np.where(hi > 0.0, hi, 1.0)
    ratio = lo / safe_hi
    out = hi * (1.0 + ratio ** (1.0 / t)) ** t
    return np.where(hi > 0.0, out, 0.0)


def as_points(points: ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Validate and return an (N, 3) float64 array."""
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == 3:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    return arr


@dataclass
class Superquadric:
    """One superquadric with a pose in the world frame.

    Attributes:
        eps1: shape exponent along the local z axis, in [EPS_MIN, EPS_MAX].
        eps2: shape exponent of the xy cross-section, in [EPS_MIN, EPS_MAX].
        scale: semi-axes (ax, ay, az) in metres, all > 0.
        rotation: 3x3 rotation matrix, local to world; its columns are the local axes in the world.
        translation: centre in the world frame, metres.
    """

    eps1: float
    eps2: float
    scale: NDArray[np.float64]
    rotation: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    translation: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        self.eps1 = float(self.eps1)
        self.eps2 = float(self.eps2)
        self.scale = np.asarray(self.scale, dtype=np.float64).reshape(3)
        self.rotation = np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)
        self.translation = np.asarray(self.translation, dtype=np.float64).reshape(3)
        values = np.concatenate(
            [[self.eps1, self.eps2], self.scale, self.rotation.ravel(), self.translation]
        )
        if not np.all(np.isfinite(values)):
            raise ValueError(f"superquadric parameters must be finite, got {self!r}")
        if not (
            EPS_MIN - 1e-9 <= self.eps1 <= EPS_MAX + 1e-9
            and EPS_MIN - 1e-9 <= self.eps2 <= EPS_MAX + 1e-9
        ):
            raise ValueError(
                f"eps1, eps2 must lie in [{EPS_MIN}, {EPS_MAX}], got {self.eps1}, {self.eps2}"
            )
        if np.any(self.scale <= 0):
            raise ValueError(f"scales must be positive metres, got {self.scale}")
        if (
            not np.allclose(self.rotation.T @ self.rotation, np.eye(3), atol=1e-6)
            or np.linalg.det(self.rotation) < 0
        ):
            raise ValueError("rotation must be a proper rotation matrix (orthonormal, det +1)")

    # ----------------------------------------------------------------- frames and parameters
    def to_local(self, points: ArrayLike) -> NDArray[np.float64]:
        """World points (N, 3) -> local frame: ``R^T (p - t)``."""
        return (as_points(points) - self.translation) @ self.rotation

    def to_world(self, points: ArrayLike) -> NDArray[np.float64]:
        """Local points (N, 3) -> world frame: ``R p + t``."""
        return as_points(points) @ self.rotation.T + self.translation

    def to_vector(self) -> NDArray[np.float64]:
        """Flat parameters ``[eps1, eps2, ax, ay, az, rx, ry, rz, tx, ty, tz]`` (rotation vector in rad)."""
        rotvec = Rotation.from_matrix(self.rotation).as_rotvec()
        return np.concatenate([[self.eps1, self.eps2], self.scale, rotvec, self.translation])

    @classmethod
    def from_vector(cls, params: ArrayLike) -> Superquadric:
        """Inverse of :meth:`to_vector`."""
        p = np.asarray(params, dtype=np.float64).reshape(N_PARAMS)
        rotation = Rotation.from_rotvec(p[5:8]).as_matrix()
        return cls(p[0], p[1], p[2:5], rotation, p[8:11])

    # ----------------------------------------------------------------- implicit function
    def inside_outside_pow(self, points: ArrayLike, local: bool = False) -> NDArray[np.float64]:
        """``G = F^eps1``, finite everywhere; < 1 inside, 1 on the surface, > 1 outside."""
        p = as_points(points) if local else self.to_local(points)
        sq = (p / self.scale) ** 2
        return _phi(_phi(sq[:, 0], sq[:, 1], self.eps2), sq[:, 2], self.eps1)

    def inside_outside(self, points: ArrayLike) -> NDArray[np.float64]:
        """F at world points (N,); clipped to a large finite value far outside."""
        g = self.inside_outside_pow(points)
        with np.errstate(divide="ignore"):
            log_f = np.log(g) / self.eps1
        return np.exp(np.clip(log_f, -_LOG_F_MAX, _LOG_F_MAX))

    def surface_radius(self, directions: ArrayLike, local: bool = False) -> NDArray[np.float64]:
        """Distance from the centre to the surface along each direction (N,), metres."""
        d = as_points(directions, "directions")
        if not local:
            d = d @ self.rotation
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        n = d / np.where(norm > 0, norm, 1.0)
        n[norm[:, 0] == 0] = (0.0, 0.0, 1.0)
        return 1.0 / np.sqrt(self.inside_outside_pow(n, local=True))

    def radial_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """``|p - c| * |1 - F^(-eps1/2)|``: distance to the surface along the ray from the centre (N,), m.

        At the centre itself the ray is undefined; the smallest semi-axis is returned there.
        """
        local = self.to_local(points)
        r = np.linalg.norm(local, axis=1)
        radius = self.surface_radius(local, local=True)
        return np.where(r > 0, np.abs(r - radius), np.min(self.scale))
