"""EM with switching (EMS) for one superquadric in a cloud with outliers.

Model (Liu et al., CVPR 2022, adopted by the paper): a point is an outlier with probability
``w_o``, uniform over the workspace volume V (density 1/V), or an inlier drawn from an isotropic
Gaussian of std sigma around the surface, measured by the scaled radial distance ``d``
(:mod:`hsqbench.planner.hsq.stage_one.radial`). The paper infers the same model with the optimisation-based
Gibbs sampler of Wu et al. (ECCV 2022); we use EM, its deterministic counterpart. Points carry
weights ``c_i``, the number of input points a voxel centroid stands for.

- E-step: inlier posterior ``p_i = 1 / (1 + k exp(d_i² / 2 sigma²))`` with
  ``k = w_o (1/V) / ((1 - w_o) (2 pi sigma²)^(-3/2))``.
- M-step: ``lm_steps`` Levenberg-Marquardt steps on ``sum_i c_i p_i d_i²``, as reweighted least
  squares on the radial distance with its exact Jacobian (:meth:`_Fitter._m_step`; eps and
  scales clipped to their bounds), then ``sigma² = sum c p d² / (3 sum c p)``, floored at
  ``sigma_min_m²``.
- Annealing (hidden parts only): after t EM iterations sigma is at least
  ``sigma_0 sigma_decay^t``, sigma_0 the starting noise level. Voxel centroids fit a local patch
  so tightly that sigma would otherwise collapse within a few iterations to a band (about five
  sigma at a high w_o) narrower than the spacing of the centroids, and a seed stops growing
  along its part. Annealing, the classic cure for EM's poor local optima, keeps the band wide
  while the seed grows and narrows it to the noise afterwards: 286 of 288 parts of the test
  unions found (48 poses) instead of 284. Whole-object fits need no growth and do not anneal.
- Cost: the negative log-likelihood of the mixture per input point,
  ``-sum c log((1 - w_o) N(d; sigma) + w_o / V) / sum c`` in nats; EM stops when it falls by
  less than ``em_tolerance`` in an iteration.
- Switching, as in EMS: the first ``max_switches`` times EM stalls (the cost falls by less than
  ``switch_tolerance`` in an iteration, which happens early, while sigma is still large), the
  posterior is held fixed and candidate superquadrics describing a similar surface with other
  parameters are ranked by ``sum c p d²``; the ``switch_candidates`` best get
  ``switch_iterations`` LM steps each, and the best of them replaces the solution if it lowers
  ``sum c p d²`` by the fraction ``switch_gain``. With the posterior fixed, a candidate wins by
  explaining the current inliers better, not by reaching for other points, so a hidden-part seed
  keeps to its part. Candidates: the two cyclic permutations of the axes with eps1 and eps2
  swapped (each axis in turn becomes the z axis), and, in each of the three frames whose x and y
  scales are within ``dual_scale_ratio``, the cross-section duality ``eps2 -> 2 - eps2`` with a
  45 degree turn about z (a square of half side a is a diamond of half diagonal a sqrt(2); the
  scale goes to ``a 2^((1 - eps2) / 2)``, exact at eps2 = 0, 1, 2). These escape the two usual
  local minima: a wrong symmetry axis, and a near-square cross-section fitted on the wrong
  branch of eps2.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.hsq.config import RecoveryConfig
from hsqbench.planner.hsq.stage_one.radial import (
    Evaluation,
    SQState,
    apply_increment,
    complete,
    evaluate,
    jacobian,
    partial_evaluate,
)

Array = NDArray[np.float64]


def _solve_or_nan(a: Array, b: Array) -> Array:
    """``np.linalg.solve``, with NaN where it would raise for a singular system."""
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        return np.full_like(b, np.nan)


try:  # np.linalg.solve's own gufunc (private, so looked up once, with a public fallback)
    from numpy.linalg._umath_linalg import solve1 as _solve
except ImportError:  # pragma: no cover - a numpy that moved it
    _solve = _solve_or_nan

_LOG_2PI = float(np.log(2.0 * np.pi))
#: Cap on the log odds of a point (exp(700) is finite; no real point comes near it).
_LOG_ODDS_MAX = 700.0
#: Largest change of a log-scale in one LM step; keeps exp() finite on a wild step.
_MAX_LOG_STEP = 2.0
#: Levenberg-Marquardt damping: start, bounds, and the factors on success and failure.
_LAMBDA = (1e-2, 1e-7, 1e7, 0.3, 10.0)


@dataclass(frozen=True)
class MixtureModel:
    """The fixed parts of the model: outlier weight and workspace volume (m³)."""

    outlier_weight: float
    volume_m3: float

    @cached_property
    def _log_out(self) -> float:
        """``ln(w_o / V)``, as ``ln w_o - ln V``."""
        return np.log(self.outlier_weight) - np.log(self.volume_m3)

    @cached_property
    def _log_odds_prior(self) -> float:
        """``ln w_o - ln V - ln(1 - w_o)``: the part of ``ln k`` that does not depend on sigma."""
        return self._log_out - np.log1p(-self.outlier_weight)

    def log_k(self, sigma2: float) -> float:
        """``ln k``: the outlier-to-inlier density ratio at zero distance, prior included."""
        return float(self._log_odds_prior + 1.5 * (_LOG_2PI + np.log(sigma2)))

    def odds(self, d: Array, sigma2: float) -> Array:
        """Inlier-to-outlier density ratio of each point, ``exp(-ln k - d² / 2 sigma²)``."""
        return np.exp(np.minimum(-self.log_k(sigma2) - d * d / (2.0 * sigma2), _LOG_ODDS_MAX))

    def posterior(self, d: Array, sigma2: float) -> Array:
        """Inlier posterior of each point (N,)."""
        return _posterior(self.odds(d, sigma2))

    def nll(self, d: Array, sigma2: float, weights: Array) -> float:
        """Negative log-likelihood per point (nats), each point counted ``weights`` times:
        ``-log(w_o / V) - log(1 + odds)`` averaged."""
        return self.nll_of_odds(self.odds(d, sigma2), weights)

    def nll_of_odds(self, odds: Array, weights: Array) -> float:
        """:meth:`nll` from the points' :meth:`odds`."""
        return float(-self._log_out - weights @ np.log1p(odds) / weights.sum())


def _posterior(odds: Array) -> Array:
    return odds / (1.0 + odds)


@dataclass
class EMSResult:
    """Outcome of one EMS run on the (downsampled) points it was given.

    Attributes:
        state: the fitted superquadric.
        posterior: (N,) inlier posterior of each point at the end.
        sigma_m: noise std, metres.
        cost: negative log-likelihood per input point, nats.
        iterations: EM iterations run, those of switching candidates included.
        switches: how many switching rounds replaced the solution.
        stopped: the ``stop`` test of :func:`ems_fit` ended the run early.
    """

    state: SQState
    posterior: Array
    sigma_m: float
    cost: float
    iterations: int
    switches: int
    stopped: bool = False


@dataclass
class _Point:
    """Where EM stands: state, its evaluation, sigma², cost, and the odds behind the cost (kept
    for the next E-step's posterior, which needs the same exponentials)."""

    state: SQState
    ev: Evaluation
    sigma2: float
    cost: float
    odds: Array

    def posterior(self) -> Array:
        return _posterior(self.odds)


class _Fitter:
    """One EMS run: the points, the model, the bounds and the iteration counter."""

    def __init__(
        self,
        points: Array,
        weights: Array,
        model: MixtureModel,
        scale_max_m: float,
        cfg: RecoveryConfig,
        stop: Callable[[Array], bool] | None = None,
        sigma_decay: float = 0.0,
    ) -> None:
        self.stop = stop
        self.sigma_decay = sigma_decay
        self.stopped = False
        self.points_t = np.ascontiguousarray(points.T)
        self.weights = weights
        self.model = model
        self.cfg = cfg
        self.eps_bounds = (cfg.eps_min, cfg.eps_max)
        self.scale_bounds = (cfg.scale_min_m, max(scale_max_m, cfg.scale_min_m))
        self.sigma2_min = cfg.sigma_min_m**2
        self.sigma2_start = self.sigma2_min
        self.iterations = 0

    def _sigma2(self, ev: Evaluation, w: Array, fallback: float) -> float:
        """M-step for sigma², floored by the annealing schedule (module doc)."""
        total = float(w.sum())
        sigma2 = float(w @ (ev.d * ev.d)) / (3.0 * total) if total > 0.0 else fallback
        if self.sigma_decay > 0.0:  # t = iterations done before this one
            sigma2 = max(sigma2, self.sigma2_start * self.sigma_decay ** (2 * self.iterations))
        return max(sigma2, self.sigma2_min)

    def _at(self, state: SQState, sigma2: float) -> _Point:
        return self._point(state, evaluate(self.points_t, state), sigma2)

    def _point(self, state: SQState, ev: Evaluation, sigma2: float) -> _Point:
        odds = self.model.odds(ev.d, sigma2)
        return _Point(state, ev, sigma2, self.model.nll_of_odds(odds, self.weights), odds)

    def _m_step(
        self, state: SQState, ev: Evaluation, w: Array, lam: float, steps: int
    ) -> tuple[SQState, Evaluation, float]:
        """``steps`` LM steps on ``sum w cos0² r²``: the radial residual r reweighted by the
        slope factor ``cos0`` of the starting state, held fixed (iteratively reweighted least
        squares; at the start ``cos0 r = d``). The Jacobian of r is exact, so a damped step
        always makes progress.

        Returns the state, its evaluation and the final damping.
        """
        wc = w * ev.cos * ev.cos
        cost = float(wc @ (ev.r * ev.r))
        fresh = True
        for _ in range(steps):
            if fresh:
                jac = jacobian(ev)
                wj = jac * wc
                h = wj @ jac.T
                minus_g = -(wj @ ev.r)  # solving for -g gives the step itself, exactly
                diag = h.diagonal().copy()
                np.maximum(diag, 1e-12 * max(float(diag.max()), 1e-300), out=diag)
                scaling = np.diag(diag)  # as a matrix: damped in two operations, h + 0 = h
            damped = lam * scaling
            damped += h
            # np.linalg.solve's own gufunc: its wrapper's checks and error-state context cost
            # more than the 11 x 11 solve. Where the wrapper raises LinAlgError (a singular
            # system) this gives NaN, and the NaN step fails the cost test below just the same.
            delta = _solve(damped, minus_g)
            log_steps = delta[2:5]  # clipped in place (np.clip costs more on 3 numbers)
            np.minimum(
                np.maximum(log_steps, -_MAX_LOG_STEP, out=log_steps), _MAX_LOG_STEP, out=log_steps
            )
            trial = apply_increment(state, delta, self.eps_bounds, self.scale_bounds)
            part = partial_evaluate(self.points_t, trial)  # completed only if accepted
            trial_cost = float(wc @ (part.r * part.r))
            fresh = math.isfinite(trial_cost) and trial_cost < cost
            if fresh:
                state, ev, cost = trial, complete(part), trial_cost
                lam = max(lam * _LAMBDA[3], _LAMBDA[1])
            else:
                lam = min(lam * _LAMBDA[4], _LAMBDA[2])
        return state, ev, lam

    def _run(self, at: _Point, max_iter: int, tolerance: float) -> _Point:
        """EM until the cost falls by less than ``tolerance`` in one iteration, or ``max_iter``."""
        lam = _LAMBDA[0]
        for _ in range(max_iter):
            p = at.posterior()
            if self.stop is not None and self.stop(p):
                self.stopped = True
                break
            w = self.weights * p
            state, ev, lam = self._m_step(at.state, at.ev, w, lam, self.cfg.lm_steps)
            new = self._point(state, ev, self._sigma2(ev, w, at.sigma2))
            self.iterations += 1
            if not np.isfinite(new.cost):
                break
            improved = at.cost - new.cost
            if new.cost < at.cost:
                at = new
            if improved < tolerance:
                break
        return at

    # ------------------------------------------------------------------ switching
    def candidates(self, state: SQState) -> list[SQState]:
        """Similar-surface alternatives of ``state`` (see the module docstring)."""
        out: list[SQState] = []
        for shift in (0, 1, 2):
            perm = np.roll(np.arange(3), -shift)
            e1, e2 = (state.eps1, state.eps2) if shift == 0 else (state.eps2, state.eps1)
            frame = SQState(
                e1, e2, state.scale[perm], state.rotation[:, perm], state.translation.copy()
            )
            if shift > 0:
                out.append(frame)
            ratio = min(frame.scale[0], frame.scale[1]) / max(frame.scale[0], frame.scale[1])
            if ratio >= self.cfg.dual_scale_ratio:
                out.append(self._dual(frame))
        return out

    def _dual(self, state: SQState) -> SQState:
        c, s = np.cos(np.pi / 4), np.sin(np.pi / 4)
        turn = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        a = 0.5 * (state.scale[0] + state.scale[1]) * 2.0 ** ((1.0 - state.eps2) / 2.0)
        scale = np.clip(np.array([a, a, state.scale[2]]), *self.scale_bounds)
        eps2 = float(np.clip(2.0 - state.eps2, *self.eps_bounds))
        return SQState(state.eps1, eps2, scale, state.rotation @ turn, state.translation.copy())

    def _switch(self, at: _Point) -> _Point | None:
        """One switching round, as in EMS: the posterior stays fixed, so a candidate wins by
        explaining the current inliers better, not by reaching for other points.

        Candidates are ranked by ``sum w d²`` as they stand; the ``switch_candidates`` best get
        ``switch_iterations`` LM steps each, and the best of those replaces ``at`` if it lowers
        ``sum w d²`` by more than the fraction ``switch_gain``.
        """
        w = self.weights * at.posterior()
        current = float(w @ (at.ev.d * at.ev.d))
        scored = []
        for cand in self.candidates(at.state):
            ev = evaluate(self.points_t, cand)
            scored.append((float(w @ (ev.d * ev.d)), cand, ev))
        scored.sort(key=lambda item: item[0])
        best = None
        for _, cand, ev in scored[: self.cfg.switch_candidates]:
            state, ev, _ = self._m_step(cand, ev, w, _LAMBDA[0], self.cfg.switch_iterations)
            cost = float(w @ (ev.d * ev.d))
            self.iterations += 1
            if best is None or cost < best[0]:
                best = (cost, state, ev)
        if best is None or best[0] > (1.0 - self.cfg.switch_gain) * current:
            return None
        _, state, ev = best
        return self._point(state, ev, self._sigma2(ev, w, at.sigma2))

    # ------------------------------------------------------------------ driver
    def fit(self, init: SQState, sigma2: float, max_switches: int) -> EMSResult:
        """EM with up to ``max_switches`` switching rounds at stalls, then EM to convergence."""
        self.sigma2_start = max(sigma2, self.sigma2_min)
        at = self._at(init, self.sigma2_start)
        switches = 0
        for _ in range(max_switches):
            at = self._run(at, self.cfg.em_max_iterations, self.cfg.switch_tolerance)
            better = None if self.stopped else self._switch(at)
            if better is not None:
                at = better
                switches += 1
        if not self.stopped:
            at = self._run(at, self.cfg.em_max_iterations, self.cfg.em_tolerance)
        return EMSResult(
            at.state,
            at.posterior(),
            float(np.sqrt(at.sigma2)),
            at.cost,
            self.iterations,
            switches,
            self.stopped,
        )


def ems_fit(
    points: Array,
    weights: Array,
    init: SQState,
    model: MixtureModel,
    sigma2_init: float,
    scale_max_m: float,
    max_switches: int,
    cfg: RecoveryConfig,
    stop: Callable[[Array], bool] | None = None,
    sigma_decay: float = 0.0,
) -> EMSResult:
    """Fit one superquadric to ``points`` (N, 3) by EMS from ``init``.

    Args:
        points: the (downsampled) cloud, metres.
        weights: (N,) how many input points each point stands for (voxel counts).
        init: the starting superquadric.
        model: outlier weight and workspace volume.
        sigma2_init: starting noise variance (m²).
        scale_max_m: upper bound on every semi-axis (m).
        max_switches: switching rounds.
        cfg: iteration counts, bounds and tolerances.
        stop: called with the posterior before every E-step; True ends the run there.
        sigma_decay: annealing factor per EM iteration of the floor on sigma (0: none).
    """
    fitter = _Fitter(points, weights, model, scale_max_m, cfg, stop, sigma_decay)
    return fitter.fit(init, sigma2_init, max_switches)
