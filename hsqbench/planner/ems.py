"""EM with switching (EMS) for one superquadric in a cloud with outliers.

Model (Liu et al., CVPR 2022, adopted by the paper): a point is an outlier with probability
``w_o``, uniform over the workspace volume V (density 1/V), or an inlier drawn from an isotropic
Gaussian of std sigma around the surface, measured here by the signed radial distance ``r``
(:mod:`hsqbench.planner.radial`). The paper infers the same model with the optimisation-based
Gibbs sampler of Wu et al. (ECCV 2022); we use EM, its deterministic counterpart:

- E-step: inlier posterior ``p_i = 1 / (1 + k exp(r_i² / 2 sigma²))`` with
  ``k = w_o (1/V) / ((1 - w_o) (2 pi sigma²)^(-3/2))``.
- M-step: a few Levenberg-Marquardt steps on ``sum_i p_i r_i²`` (analytic Jacobian, eps and
  scales clipped to their bounds), then ``sigma² = sum p r² / (3 sum p)``, floored.
- Cost: the negative log-likelihood of the mixture per point,
  ``-mean log((1 - w_o) N(r; sigma) + w_o / V)`` in nats.
- Switching: when the cost stalls, candidate superquadrics that describe a similar surface with
  other parameters are tried, and the best one (after a few EM iterations each) is kept if it
  lowers the cost. Candidates: the two cyclic permutations of the axes (so each axis in turn
  becomes z, with eps1 and eps2 as they are or swapped), and, in each such frame whose x and y
  scales are close, the cross-section duality ``eps2 -> 2 - eps2`` with a 45 degree turn about z
  (a square with half side a is a diamond with half diagonal a sqrt(2): the scale goes to
  ``a 2^((1 - eps2) / 2)``). These escape the two usual local minima: a wrong choice of the
  symmetry axis, and a near-square cross-section fitted with the wrong eps2 branch.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.special import expit

from hsqbench.planner.config import RecoveryConfig
from hsqbench.planner.radial import SQState, apply_increment, radial_residual

Array = NDArray[np.float64]

_LOG_2PI = float(np.log(2.0 * np.pi))
#: Largest change of a log-scale in one LM step; keeps exp() finite on a wild step.
_MAX_LOG_STEP = 2.0


@dataclass(frozen=True)
class MixtureModel:
    """The fixed parts of the model: outlier weight and workspace volume (m³)."""

    outlier_weight: float
    volume_m3: float

    def log_k(self, sigma2: float) -> float:
        """``ln k``: the outlier-to-inlier density ratio at zero distance, prior included."""
        w = self.outlier_weight
        return float(
            np.log(w) - np.log(self.volume_m3) - np.log1p(-w) + 1.5 * (_LOG_2PI + np.log(sigma2))
        )

    def posterior(self, r: Array, sigma2: float) -> Array:
        """Inlier posterior of each point (N,)."""
        return expit(-(self.log_k(sigma2) + r * r / (2.0 * sigma2)))

    def nll(self, r: Array, sigma2: float, weights: Array) -> float:
        """Negative log-likelihood per point (nats), each point counted ``weights`` times."""
        w = self.outlier_weight
        log_in = np.log1p(-w) - 1.5 * (_LOG_2PI + np.log(sigma2)) - r * r / (2.0 * sigma2)
        log_out = np.log(w) - np.log(self.volume_m3)
        return float(-(weights @ np.logaddexp(log_in, log_out)) / weights.sum())


@dataclass
class EMSResult:
    """Outcome of one EMS run on the (downsampled) points it was given."""

    state: SQState
    posterior: Array
    sigma_m: float
    cost: float
    iterations: int
    switches: int


class _Fitter:
    """One EMS run: the points, the model, the bounds and the iteration counters."""

    def __init__(
        self,
        points: Array,
        weights: Array,
        model: MixtureModel,
        scale_max_m: float,
        cfg: RecoveryConfig,
    ) -> None:
        self.points = points
        self.weights = weights
        self.model = model
        self.cfg = cfg
        self.eps_bounds = (cfg.eps_min, cfg.eps_max)
        self.scale_bounds = (cfg.scale_min_m, max(scale_max_m, cfg.scale_min_m))
        self.sigma2_min = cfg.sigma_min_m**2
        self.iterations = 0

    # ------------------------------------------------------------------ building blocks
    def _sigma2(self, r: Array, p: Array) -> float:
        wp = self.weights * p
        total = float(wp.sum())
        if total <= 0.0:
            return max(float(np.mean(r * r) / 3.0), self.sigma2_min)
        return max(float(wp @ (r * r)) / (3.0 * total), self.sigma2_min)

    def _m_step(self, state: SQState, p: Array, lam: float) -> tuple[SQState, float]:
        """A few LM steps on ``sum p r²`` over the points that still carry weight."""
        active = p > self.cfg.active_weight
        if int(active.sum()) < state.scale.size + 8:
            active = np.ones_like(p, dtype=bool)
        x, w = self.points[active], (self.weights * p)[active]
        r, jac = radial_residual(x, state, jacobian=True)
        cost = float(w @ (r * r))
        for _ in range(self.cfg.lm_steps):
            wj = jac * w[:, None]
            h = jac.T @ wj
            g = wj.T @ r
            diag = np.diag(h).copy()
            diag = np.maximum(diag, 1e-12 * max(float(diag.max()), 1e-300))
            try:
                delta = -np.linalg.solve(h + lam * np.diag(diag), g)
            except np.linalg.LinAlgError:
                lam *= 10.0
                continue
            delta[2:5] = np.clip(delta[2:5], -_MAX_LOG_STEP, _MAX_LOG_STEP)
            trial = apply_increment(state, delta, self.eps_bounds, self.scale_bounds)
            r_new, jac_new = radial_residual(x, trial, jacobian=True)
            cost_new = float(w @ (r_new * r_new))
            if np.isfinite(cost_new) and cost_new < cost:
                state, r, jac, cost = trial, r_new, jac_new, cost_new
                lam = max(lam * 0.3, 1e-7)
            else:
                lam = min(lam * 10.0, 1e7)
        return state, lam

    def _run(
        self, state: SQState, sigma2: float, max_iter: int
    ) -> tuple[SQState, float, float, Array]:
        """Plain EM until the cost stalls or ``max_iter``; returns state, sigma², cost, residuals."""
        r, _ = radial_residual(self.points, state)
        cost = self.model.nll(r, sigma2, self.weights)
        lam = 1e-2
        for _ in range(max_iter):
            p = self.model.posterior(r, sigma2)
            new_state, lam = self._m_step(state, p, lam)
            new_r, _ = radial_residual(self.points, new_state)
            new_sigma2 = self._sigma2(new_r, p)
            new_cost = self.model.nll(new_r, new_sigma2, self.weights)
            self.iterations += 1
            if not np.isfinite(new_cost):
                break
            improved = cost - new_cost
            if new_cost < cost:
                state, r, sigma2, cost = new_state, new_r, new_sigma2, new_cost
            if improved < self.cfg.em_tolerance:
                break
        return state, sigma2, cost, r

    # ------------------------------------------------------------------ switching
    def candidates(self, state: SQState) -> list[SQState]:
        """Similar-surface alternatives of ``state`` (see the module docstring)."""
        out: list[SQState] = []
        for shift in (0, 1, 2):
            perm = np.roll(np.arange(3), -shift)
            rot = state.rotation[:, perm]
            scale = state.scale[perm]
            eps_pairs = [(state.eps1, state.eps2), (state.eps2, state.eps1)]
            if state.eps1 == state.eps2:
                eps_pairs = eps_pairs[:1]
            for e1, e2 in eps_pairs:
                if shift > 0 or (e1, e2) != (state.eps1, state.eps2):
                    out.append(SQState(e1, e2, scale.copy(), rot.copy(), state.translation.copy()))
                ratio = min(scale[0], scale[1]) / max(scale[0], scale[1])
                if ratio >= self.cfg.dual_scale_ratio:
                    out.append(self._dual(SQState(e1, e2, scale, rot, state.translation)))
        return out

    def _dual(self, state: SQState) -> SQState:
        c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        a = 0.5 * (state.scale[0] + state.scale[1]) * 2.0 ** ((1.0 - state.eps2) / 2.0)
        scale = np.clip(np.array([a, a, state.scale[2]]), *self.scale_bounds)
        eps2 = float(np.clip(2.0 - state.eps2, *self.eps_bounds))
        return SQState(state.eps1, eps2, scale, state.rotation @ turn, state.translation.copy())

    # ------------------------------------------------------------------ driver
    def fit(self, init: SQState, sigma2: float, max_switches: int) -> EMSResult:
        sigma2 = max(sigma2, self.sigma2_min)
        state, sigma2, cost, r = self._run(init, sigma2, self.cfg.em_max_iterations)
        switches = 0
        while switches < max_switches and self.iterations < self.cfg.em_max_iterations * 4:
            best = None
            for cand in self.candidates(state):
                c_state, c_sigma2, c_cost, c_r = self._run(cand, sigma2, self.cfg.switch_iterations)
                if best is None or c_cost < best[2]:
                    best = (c_state, c_sigma2, c_cost, c_r)
            if best is None or best[2] > cost - self.cfg.em_tolerance:
                break
            switches += 1
            state, sigma2, cost, r = self._run(best[0], best[1], self.cfg.em_max_iterations)
            if cost > best[2]:
                state, sigma2, cost, r = best
        posterior = self.model.posterior(r, sigma2)
        return EMSResult(state, posterior, float(np.sqrt(sigma2)), cost, self.iterations, switches)


def ems_fit(
    points: Array,
    weights: Array,
    init: SQState,
    model: MixtureModel,
    sigma2_init: float,
    scale_max_m: float,
    max_switches: int,
    cfg: RecoveryConfig,
) -> EMSResult:
    """Fit one superquadric to ``points`` (N, 3) by EMS from ``init``.

    Args:
        points: the (downsampled) cloud, metres.
        weights: (N,) how many input points each point stands for (voxel counts).
        init: the starting superquadric.
        model: outlier weight and workspace volume.
        sigma2_init: starting noise variance (m²).
        scale_max_m: upper bound on every semi-axis (m).
        max_switches: how many times switching may replace the current solution.
        cfg: iteration counts, bounds and tolerances.
    """
    fitter = _Fitter(points, weights, model, scale_max_m, cfg)
    return fitter.fit(init, sigma2_init, max_switches)
