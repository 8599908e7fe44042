"""Many superquadrics evaluated at once: one superquadric's shape per row.

Stage two asks the same questions of points that belong to different superquadrics (where does a
line leave the surface, which way does the surface face there). Giving each
row its own ``scale``, ``eps1`` and ``eps2`` answers them for all lines in one vectorised call
instead of a Python loop over superquadrics. Points are in each row's local frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

# _phi is the superquadric module's overflow-free power sum; its t may be an array.
from hsqbench.superquadric.geometry import Superquadric
from hsqbench.superquadric.primitives import _phi

#: Bisection steps for contact distances: 2^-40 of the superquadric's size, far below noise.
_BISECTION_STEPS = 40
#: Finite-difference step for the gradient, as a fraction of the row's largest semi-axis: near the
#: optimum for central differences of a function of order 1 in float64.
_GRAD_STEP = 1e-6


@dataclass(frozen=True)
class ShapeRows:
    """Shape parameters of one superquadric per row, so that many superquadrics' points are
    evaluated in one vectorised call: ``scale`` (n, 3) metres, ``eps1`` and ``eps2`` (n,)."""

    scale: NDArray[np.float64]
    eps1: NDArray[np.float64]
    eps2: NDArray[np.float64]

    def __getitem__(self, index: NDArray) -> ShapeRows:
        return ShapeRows(self.scale[index], self.eps1[index], self.eps2[index])

    @classmethod
    def of(cls, superquadrics: Sequence[Superquadric], index: NDArray[np.int64]) -> ShapeRows:
        scale = np.array([sq.scale for sq in superquadrics]).reshape(-1, 3)
        eps = np.array([(sq.eps1, sq.eps2) for sq in superquadrics]).reshape(-1, 2)
        return cls(scale[index], eps[index, 0], eps[index, 1])

    def inside_outside_pow(self, local: NDArray) -> NDArray[np.float64]:
        """``G = F^eps1`` of each row's superquadric at its local point (n, 3), stable form."""
        q = (local / self.scale) ** 2
        return _phi(_phi(q[:, 0], q[:, 1], self.eps2), q[:, 2], self.eps1)

    def contact_distance(self, origins: NDArray, directions: NDArray) -> NDArray[np.float64]:
        """Distance ``t >= 0`` from local ``origins`` (n, 3), inside, to the surface along local
        unit ``directions`` (n, 3), by bisection on ``G`` (metres). The superquadrics are convex
        (eps <= 2), so ``G`` crosses 1 once along each ray."""
        lo = np.zeros(origins.shape[0])
        hi = 2.0 * np.linalg.norm(self.scale, axis=1)
        for _ in range(_BISECTION_STEPS):
            mid = 0.5 * (lo + hi)
            outside = self.inside_outside_pow(origins + mid[:, None] * directions) >= 1.0
            hi = np.where(outside, mid, hi)
            lo = np.where(outside, lo, mid)
        return 0.5 * (lo + hi)

    def gradient(self, local: NDArray) -> NDArray[np.float64]:
        """Gradient of ``G`` at local points (n, 3), central differences (outward on the surface)."""
        step = _GRAD_STEP * np.max(self.scale, axis=1)
        grad = np.empty_like(local)
        for k in range(3):
            e = np.zeros_like(local)
            e[:, k] = step
            grad[:, k] = (
                self.inside_outside_pow(local + e) - self.inside_outside_pow(local - e)
            ) / (2 * step)
        return grad
