"""Candidate sets: roll frames, per-candidate views and the lazy ranking."""

from __future__ import annotations

import numpy as np

from hsqbench.planner.hsq.stage_two.candidates import (
    CandidateSet,
    ClosingLines,
    RankedGrasps,
    roll_frames,
)


def lines(n: int, rng: np.random.Generator) -> ClosingLines:
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    e1 = np.cross(d, rng.normal(size=(n, 3)))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return ClosingLines(
        centres=rng.normal(size=(n, 3)),
        directions=d,
        approach0=e1,
        half_lengths=rng.uniform(0.01, 0.03, size=n),
        source=np.arange(n),
        axis=np.zeros(n, dtype=np.int64),
        family=np.array(["axis"] * n),
    )


def test_roll_frames_are_rotations_about_the_closing_line() -> None:
    rng = np.random.default_rng(0)
    L = lines(4, rng)
    rolls = np.deg2rad(np.arange(0, 360, 30.0))
    frames = roll_frames(L.directions, L.approach0, rolls)
    np.testing.assert_allclose(
        np.einsum("lrji,lrjk->lrik", frames, frames),
        np.broadcast_to(np.eye(3), frames.shape),
        atol=1e-12,
    )
    np.testing.assert_allclose(np.linalg.det(frames), 1.0)
    np.testing.assert_allclose(
        frames[:, :, :, 0], np.broadcast_to(L.directions[:, None], (4, 12, 3))
    )
    np.testing.assert_allclose(frames[:, 0, :, 2], L.approach0)  # roll 0 approaches along e1
    # Roll 90 degrees approaches along e2 = d x e1.
    np.testing.assert_allclose(frames[:, 3, :, 2], np.cross(L.directions, L.approach0), atol=1e-12)


def test_candidate_views_agree_with_single_grasps() -> None:
    rng = np.random.default_rng(1)
    cands = CandidateSet(lines(3, rng), np.deg2rad(np.arange(0, 360, 45.0)))
    cands.scores = rng.uniform(size=len(cands))
    rotations, positions, widths = cands.rotations, cands.positions, cands.widths
    for i in (0, 5, 13, 23):
        g = cands.grasp(i)
        np.testing.assert_allclose(g.rotation, rotations[i], atol=1e-12)
        np.testing.assert_allclose(g.position, positions[i])
        assert g.width == widths[i] and g.source == cands.line_index[i]
        assert g.score == cands.scores[i]


def test_ranking_is_by_score_and_skips_rejected() -> None:
    rng = np.random.default_rng(2)
    cands = CandidateSet(lines(2, rng), np.deg2rad([0.0, 90.0, 180.0]))
    cands.scores = np.array([0.2, 0.9, 0.5, 0.9, 0.1, 0.7])
    cands.rejected_by[[3, 5]] = ["collision", "support"]
    ranked = cands.ranked()
    assert isinstance(ranked, RankedGrasps) and len(ranked) == 4
    np.testing.assert_array_equal(ranked.indices, [1, 2, 0, 4])
    assert [g.score for g in ranked] == [0.9, 0.5, 0.2, 0.1]
    top = ranked[:2]
    assert len(top) == 2 and top[1].score == 0.5
    assert cands.counts_by_reason()["kept"] == 4
