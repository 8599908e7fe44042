"""EMS: the mixture model, the switching candidates, one fit."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from hsqbench.planner.hsq.config import RecoveryConfig
from hsqbench.planner.hsq.stage_one import ems
from hsqbench.planner.hsq.stage_one.ems import MixtureModel, _Fitter, ems_fit
from hsqbench.planner.hsq.stage_one.radial import SQState
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import add_noise_and_outliers, random_rotation, surface_distance


def test_posterior_and_likelihood() -> None:
    model = MixtureModel(0.9, 1e-3)
    sigma2 = 1e-6
    d = np.array([0.0, 0.001, 0.003, 0.05])
    p = model.posterior(d, sigma2)
    k = np.exp(model.log_k(sigma2))
    assert np.isclose(p[0], 1.0 / (1.0 + k))
    assert np.all(np.diff(p) < 0) and p[-1] < 1e-12
    # Each point counted twice = the points listed twice.
    assert np.isclose(
        model.nll(d, sigma2, np.full(4, 2.0)), model.nll(np.r_[d, d], sigma2, np.ones(8))
    )
    assert np.isfinite(model.nll(np.array([10.0]), 1e-8, np.ones(1)))


def _fitter() -> _Fitter:
    cfg = RecoveryConfig()
    return _Fitter(np.zeros((1, 3)), np.ones(1), MixtureModel(0.2, 1.0), 1.0, cfg)


def _sq(state: SQState) -> Superquadric:
    return state.to_superquadric()


def test_duality_candidate_describes_the_same_cross_section() -> None:
    """A rounded square and the diamond of the dual branch, 45 degrees turned, nearly coincide;
    a circle is its own dual."""
    fitter = _fitter()
    for eps2, tol in ((0.2, 0.0025), (1.0, 0.0008)):
        state = SQState(
            0.5,
            eps2,
            np.array([0.05, 0.05, 0.04]),
            random_rotation(np.random.default_rng(0)),
            np.zeros(3),
        )
        duals = [c for c in fitter.candidates(state) if np.isclose(c.eps2, 2.0 - eps2)]
        assert duals
        assert surface_distance(_sq(state), _sq(duals[0]), 0.001) < tol


def test_permutation_candidates_of_a_symmetric_shape_are_the_same_surface() -> None:
    fitter = _fitter()
    state = SQState(0.4, 0.4, np.array([0.02, 0.03, 0.05]), np.eye(3), np.zeros(3))
    perms = [c for c in fitter.candidates(state) if np.isclose(c.eps2, 0.4)]
    assert len(perms) == 2
    for c in perms:
        assert not np.allclose(c.scale, state.scale)
        assert surface_distance(_sq(state), _sq(c), 0.001) < 0.0008


def test_ems_recovers_a_superquadric_from_a_perturbed_start() -> None:
    rng = np.random.default_rng(1)
    sq = Superquadric(0.3, 0.7, [0.03, 0.05, 0.04], random_rotation(rng), [0.0, 0.1, 0.0])
    surface, _ = sq.sample_surface(0.003)
    pts, _ = add_noise_and_outliers(surface, 0.0005, 0.1, rng)
    start = SQState(1.0, 1.0, sq.scale * 0.8, sq.rotation, sq.translation + 0.005)
    cfg = RecoveryConfig()
    res = ems_fit(pts, np.ones(len(pts)), start, MixtureModel(0.1, 0.01), 1e-4, 0.2, 2, cfg)
    assert surface_distance(sq, _sq(res.state)) < 0.001
    assert 0.0003 < res.sigma_m < 0.001 and not res.stopped


def test_stop_hook_ends_the_run() -> None:
    pts = np.random.default_rng(2).normal(scale=0.05, size=(100, 3))
    start = SQState(1.0, 1.0, np.full(3, 0.05), np.eye(3), np.zeros(3))
    res = ems_fit(
        pts,
        np.ones(100),
        start,
        MixtureModel(0.5, 1.0),
        1e-4,
        1.0,
        2,
        RecoveryConfig(),
        lambda p: True,
    )
    assert res.stopped and res.iterations == 0


def test_annealing_floors_sigma_early_and_not_later() -> None:
    cfg = RecoveryConfig()
    pts = np.zeros((5, 3))
    fitter = _Fitter(pts, np.ones(5), MixtureModel(0.9, 1.0), 1.0, cfg, sigma_decay=0.5)
    fitter.sigma2_start = 1e-4
    state = SQState(1.0, 1.0, np.full(3, 0.05), np.eye(3), np.zeros(3))
    ev = fitter._at(state, 1e-4).ev
    # Points 5 cm off the surface. Zero weights: the estimate falls back to 1e-8 and the
    # annealing floor (then sigma_min) decides; any weight: the data, sigma² = (5 cm)² / 3.
    w = np.full(5, 1e-12)
    fitter.iterations = 3
    assert np.isclose(fitter._sigma2(ev, np.zeros(5), 1e-8), 1e-4 * 0.5**6)
    fitter.iterations = 40
    assert fitter._sigma2(ev, np.zeros(5), 1e-8) == cfg.sigma_min_m**2
    assert np.isclose(fitter._sigma2(ev, w, 1e-8), 0.05**2 / 3.0, rtol=1e-3)


@pytest.mark.parametrize("solve", [ems._solve, ems._solve_or_nan])
def test_the_lm_solve_gives_the_step_or_nan_for_a_singular_system(solve) -> None:
    rng = np.random.default_rng(0)
    m = rng.normal(size=(11, 11))
    a, b = m @ m.T + np.eye(11), rng.normal(size=11)
    assert np.allclose(solve(a, b), np.linalg.solve(a, b), rtol=1e-12, atol=0.0)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert np.isnan(solve(np.zeros((11, 11)), b)).all()
