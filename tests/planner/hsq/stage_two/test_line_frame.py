"""Cloud points in each closing line's frame, and the chunks of lines they are computed in."""

from __future__ import annotations

import numpy as np

from hsqbench.planner.hsq.stage_two import line_frame
from hsqbench.planner.hsq.stage_two.line_frame import _chunks, _line_coordinates


def _frames(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` random lines: centres, unit directions, unit approach axes perpendicular to them."""
    centres = rng.uniform(-0.2, 0.2, (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    e1 = np.cross(d, rng.normal(size=(n, 3)))
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return centres, d, e1


def test_a_point_built_from_line_coordinates_gets_them_back() -> None:
    rng = np.random.default_rng(0)
    centres, d, e1 = _frames(4, rng)
    e2 = np.cross(d, e1)
    coords = rng.uniform(-0.05, 0.05, (3, 5))  # s, u, v of 5 points about line 2
    points = centres[2] + coords[0, :, None] * d[2] + coords[1, :, None] * e1[2]
    points += coords[2, :, None] * e2[2]
    s, u, v = _line_coordinates(points, centres, d, e1)
    assert s.shape == (5, 4) and s.dtype == np.float32
    for got, want in zip((s, u, v), coords, strict=True):
        np.testing.assert_allclose(got[:, 2], want, atol=1e-6)  # float32, relative to the centre


def test_lines_first_is_the_same_numbers_transposed() -> None:
    rng = np.random.default_rng(1)
    centres, d, e1 = _frames(3, rng)
    points = rng.uniform(-0.1, 0.1, (7, 3))
    by_point = _line_coordinates(points, centres, d, e1)
    by_line = _line_coordinates(points, centres, d, e1, lines_first=True)
    for a, b in zip(by_point, by_line, strict=True):
        assert b.shape == (3, 7)
        np.testing.assert_array_equal(a, b.T)


def test_chunks_cover_every_line_once_within_the_pair_budget(monkeypatch) -> None:
    monkeypatch.setattr(line_frame, "_CHUNK_PAIRS", 1000)
    chunks = list(_chunks(n_lines=23, n_points=90))
    covered = np.concatenate([np.arange(23)[c] for c in chunks])
    np.testing.assert_array_equal(covered, np.arange(23))
    assert all((c.stop - c.start) * 90 <= 1000 for c in chunks)
    # More points than the budget: one line at a time, never an empty chunk.
    assert [c.stop - c.start for c in _chunks(n_lines=3, n_points=5000)] == [1, 1, 1]
    assert list(_chunks(n_lines=0, n_points=10)) == []
