"""Scoring: each factor responds to what it measures, in the documented units."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.scoring import FACTOR_NAMES, contact_curvature, score_candidates
from hsqbench.planner.hsq.stage_two.synthesis import synthesize
from hsqbench.superquadric.geometry import Superquadric

CONFIG = GraspConfig()


def scored(sqs, alphas=None, betas=None, centroid=(0.0, 0.0, 0.0), packed=False):
    cands = synthesize(sqs, CONFIG)
    n = len(sqs)
    alphas = np.zeros(n) if alphas is None else np.asarray(alphas)
    betas = np.ones(n) if betas is None else np.asarray(betas)
    score_candidates(cands, sqs, alphas, betas, np.asarray(centroid), packed, CONFIG)
    return cands


def test_score_is_the_product_of_the_factors() -> None:
    cands = scored([Superquadric(0.5, 0.8, [0.03, 0.02, 0.04])], [0.003], [0.7], (0.01, 0, 0))
    product = np.prod([cands.factors[k] for k in FACTOR_NAMES], axis=0)
    np.testing.assert_allclose(cands.scores, product)
    assert np.all((cands.scores > 0) & (cands.scores <= 1))


def test_alpha_and_beta_factors() -> None:
    sq = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])
    cands = scored([sq, sq], alphas=[0.0, 0.004], betas=[1.0, 0.6])
    by_source = {s: cands.factors["h_alpha"][cands.lines.source.repeat(36) == s] for s in (0, 1)}
    assert np.all(by_source[0] == 1.0)
    expected = np.exp(-((0.004 / CONFIG.alpha_unit_m) ** 2) / CONFIG.q_alpha)
    np.testing.assert_allclose(by_source[1], expected)
    h_beta = cands.factors["h_beta"][cands.lines.source.repeat(36) == 1]
    np.testing.assert_allclose(h_beta, 0.36)


def test_curvature_is_dimensionless_k_times_h_squared() -> None:
    # A sphere's lines through its centre have K h^2 = 1 at any size: h_gamma =
    # exp(-1 / q_gamma); slid chords (h < r) have K h^2 = (h / r)^2.
    for r in (0.01, 0.035):
        cands = scored([Superquadric(1.0, 1.0, [r, r, r])])
        axis = np.repeat(cands.lines.family == "axis", 36)
        np.testing.assert_allclose(cands.measures["gamma"][axis], 1.0, rtol=1e-3)
        expected = np.exp(-1 / CONFIG.q_gamma)
        np.testing.assert_allclose(cands.factors["h_gamma"][axis], expected, rtol=1e-3)
        chords = np.repeat((cands.lines.half_lengths / r) ** 2, 36)
        np.testing.assert_allclose(cands.measures["gamma"], chords, rtol=1e-2)
    # Flat faces of a box and the side of a cylinder: K = 0, h_gamma = 1.
    box = scored([Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])])
    central = np.repeat(box.lines.family == "axis", 36)
    np.testing.assert_allclose(box.factors["h_gamma"][central], 1.0, atol=1e-6)
    # Along a straight edge the surface is still developable (K = 0), but a pad patch that
    # reaches a rounded corner (slid 5 mm from two edges) is doubly curved and scores less.
    c = np.abs(box.lines.centres)
    corner = np.repeat((box.lines.axis == 0) & (c[:, 1] > 0.01) & (c[:, 2] > 0.04), 36)
    edge = np.repeat((box.lines.axis == 0) & (c[:, 1] > 0.01) & (c[:, 2] < 0.02), 36)
    assert np.any(corner) and np.any(edge)
    assert np.all(box.factors["h_gamma"][corner] < 0.5)
    np.testing.assert_allclose(box.factors["h_gamma"][edge], 1.0, atol=0.01)
    cylinder = Superquadric(0.1, 1.0, [0.02, 0.02, 0.05])
    cyl = scored([cylinder])
    middle = (np.abs(cyl.lines.directions[:, 2]) < 1e-9) & (np.abs(cyl.lines.centres[:, 2]) < 0.02)
    side = np.repeat(middle, 36)
    np.testing.assert_allclose(cyl.factors["h_gamma"][side], 1.0, atol=1e-3)


def test_ellipsoid_prefers_its_flat_sides_to_its_pointed_tip() -> None:
    sq = Superquadric(1.0, 1.0, [0.05, 0.02, 0.015])
    cands = scored([sq])
    gamma = cands.measures["gamma"][:: cands.n_roll]  # one per line: axes x, y, z
    # Tip of x: K h^2 = a^4 / (b^2 c^2) (averaged over the pad patch); sides are far flatter.
    assert gamma[0] > 10 * gamma[1] and gamma[0] > 10 * gamma[2]
    assert cands.factors["h_gamma"][0] < 1e-6 < cands.factors["h_gamma"][cands.n_roll]


def test_patch_curvature_is_left_out_past_edges() -> None:
    # A thin part: the patch radius shrinks to half its smallest semi-axis and stays on the face.
    thin = Superquadric(0.1, 0.1, [0.004, 0.03, 0.03])
    cands = synthesize([thin], CONFIG)
    k = contact_curvature([thin], cands.lines, np.arange(len(cands.lines)), CONFIG)
    assert np.all(np.isfinite(k))


def test_delta_factor_and_packed_scenes() -> None:
    sq = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05], translation=[0.05, 0.0, 0.0])
    cands = scored([sq], centroid=(0.0, 0.0, 0.0))
    delta = cands.measures["delta_m"]
    np.testing.assert_allclose(cands.factors["h_delta"], np.exp(-(delta**2) / CONFIG.q_delta))
    # delta = 5 cm gives 0.61: the paper's q_delta is sensible in metres.
    assert np.exp(-(0.05**2) / CONFIG.q_delta) == pytest.approx(0.6065, abs=1e-4)
    packed = scored([sq], centroid=(0.0, 0.0, 0.0), packed=True)
    assert "h_delta" not in packed.factors
    product = np.prod([packed.factors[k] for k in FACTOR_NAMES[:3]], axis=0)
    np.testing.assert_allclose(packed.scores, product)
    assert np.all(packed.scores >= cands.scores)


def test_rejected_candidates_have_no_score() -> None:
    sq = Superquadric(0.1, 0.1, [0.03, 0.02, 0.05])
    cands = synthesize([sq], CONFIG)
    cands.rejected_by[:36] = "support"
    score_candidates(cands, [sq], np.zeros(1), np.ones(1), np.zeros(3), False, CONFIG)
    assert np.all(np.isnan(cands.scores[:36])) and np.all(np.isfinite(cands.scores[36:]))
