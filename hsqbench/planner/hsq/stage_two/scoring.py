"""Candidate scoring (paper, stage two): ``h = h_alpha * h_beta * h_gamma * h_delta``.

- ``h_alpha = exp(-alpha_hat^2 / q_alpha)``: goodness of the superquadric's fit, with
  ``alpha_hat = alpha / alpha_unit_m`` (0.1 m: 1/e at a 4.5 mm mean error, 0.9 at the cameras'
  noise level);
- ``h_beta = beta^2``: its coverage;
- ``h_gamma = exp(-gamma^2 / q_gamma)``: flatness at the contacts, with the dimensionless
  ``gamma = mean(K) * h^2``: the mean Gaussian curvature ``K`` (1/m^2) over the pad-sized patch
  around a contact, times the squared distance ``h`` from ``P_G`` to the contact. ``K h^2`` is 0
  on flat faces and on the sides of cylinders, 1 on any sphere and ``(b/a)^2``-like on ellipsoids,
  so it ranks shapes, not sizes; in 1/m^2, any object small enough to grasp drives ``h_gamma``
  to 0 with the paper's ``q_gamma = 0.5``.
- ``h_delta = exp(-delta^2 / q_delta)``: ``delta`` in metres from ``P_G`` to the cloud's centroid
  (the paper's centre of mass); left out in packed scenes.

The q's are the paper's (0.002, 0.5, 0.005). The paper gives no units; ``alpha_unit_m`` and the
curvature normalisation are this implementation's choices, justified in ``configs/planner.yaml``.
All factors of a closing line are shared by its rolls.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import KEPT, CandidateSet, ClosingLines
from hsqbench.planner.hsq.stage_two.shape_rows import ShapeRows
from hsqbench.superquadric.curvature import gaussian_curvature_local
from hsqbench.superquadric.geometry import Superquadric

FACTOR_NAMES = ("h_alpha", "h_beta", "h_gamma", "h_delta")
#: The raw measures behind the factors: alpha (m), beta, gamma (dimensionless), delta (m).
MEASURE_NAMES = ("alpha_m", "beta", "gamma", "delta_m")

#: Contact patch: rings at these fractions of ``contact_radius_m``, this many samples each
#: (24 samples: a pad-sized patch, sampled about every 2 mm).
_RING_FRACTIONS = (1 / 3, 2 / 3, 1.0)
_RING_SAMPLES = 8


def contact_curvature(
    superquadrics: Sequence[Superquadric],
    lines: ClosingLines,
    index: NDArray[np.int64],
    config: GraspConfig,
) -> NDArray[np.float64]:
    """Mean Gaussian curvature (1/m^2) over the patch around the ``+d`` contact of lines ``index``.

    Patch samples are where lines parallel to the closing line, offset by rings of radius up to
    ``contact_radius_m`` (capped at half the smallest semi-axis so
    the patch fits on thin parts), meet the surface: where the pads touch. Offsets that miss the
    surface (past an edge) are left out; a line with no sample on the surface gets +inf. The
    ``-d`` contact has the same curvature by symmetry.
    """
    n = index.size
    if n == 0:
        return np.zeros(0)
    src = lines.source[index]
    rot = np.array([sq.rotation for sq in superquadrics]).reshape(-1, 3, 3)[src]
    trans = np.array([sq.translation for sq in superquadrics]).reshape(-1, 3)[src]
    o = np.einsum("nji,nj->ni", rot, lines.centres[index] - trans)
    d = np.einsum("nji,nj->ni", rot, lines.directions[index])
    e1 = np.einsum("nji,nj->ni", rot, lines.approach0[index])
    e2 = np.cross(d, e1)
    shapes = ShapeRows.of(superquadrics, src)
    radius = np.minimum(config.contact_radius_m, 0.5 * np.min(shapes.scale, axis=1))
    rings = []
    for k, frac in enumerate(_RING_FRACTIONS):
        ang = (np.arange(_RING_SAMPLES) + 0.5 * k) * 2 * np.pi / _RING_SAMPLES
        rings.append(frac * np.column_stack([np.cos(ang), np.sin(ang)]))
    unit = np.concatenate(rings)  # (S, 2), times each line's radius
    s = unit.shape[0]
    offsets = radius[:, None, None] * unit[None]
    starts = o[:, None] + offsets[..., :1] * e1[:, None] + offsets[..., 1:] * e2[:, None]
    starts = starts.reshape(-1, 3)
    dirs = np.repeat(d, s, axis=0)
    rows = np.repeat(np.arange(n), s)
    on = shapes[rows].inside_outside_pow(starts) < 1.0
    curv = np.full(n * s, np.nan)
    if np.any(on):
        sub = shapes[rows[on]]
        hit = starts[on] + sub.contact_distance(starts[on], dirs[on])[:, None] * dirs[on]
        curv[on] = gaussian_curvature_local(hit, sub.eps1, sub.eps2, sub.scale)
    curv = curv.reshape(n, s)
    any_on = np.any(on.reshape(n, s), axis=1)
    mean = np.full(n, np.inf)
    mean[any_on] = np.nanmean(curv[any_on], axis=1)
    return mean


def fit_factors(
    alphas: NDArray, betas: NDArray, config: GraspConfig
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(h_alpha, h_beta)`` of each hidden superquadric from its alpha (m) and beta."""
    alpha_hat = np.asarray(alphas, dtype=np.float64) / config.alpha_unit_m
    return np.exp(-(alpha_hat**2) / config.q_alpha), np.asarray(betas, dtype=np.float64) ** 2


def score_candidates(
    cands: CandidateSet,
    superquadrics: Sequence[Superquadric],
    alphas: NDArray,
    betas: NDArray,
    centroid: NDArray,
    packed: bool,
    config: GraspConfig,
) -> None:
    """Fill ``cands.scores`` and ``cands.factors`` for the surviving candidates (in place).

    Args:
        superquadrics: the hidden superquadrics, indexed by ``cands.lines.source``.
        alphas, betas: their goodness (metres) and coverage (fraction in [0, 1]).
        centroid: the cloud's centroid, metres.
        packed: leave ``h_delta`` out (the centroid of a cluttered scene means nothing).
    """
    n_roll = cands.n_roll
    L = cands.lines
    alive = np.flatnonzero(np.any(cands.rejected_by.reshape(len(L), n_roll) == KEPT, axis=1))
    line_factors = {name: np.full(len(L), np.nan) for name in FACTOR_NAMES}
    line_measures = {name: np.full(len(L), np.nan) for name in MEASURE_NAMES}
    if alive.size:
        src = L.source[alive]
        h_alpha, h_beta = fit_factors(alphas, betas, config)
        line_factors["h_alpha"][alive] = h_alpha[src]
        line_factors["h_beta"][alive] = h_beta[src]
        gamma = contact_curvature(superquadrics, L, alive, config) * L.half_lengths[alive] ** 2
        with np.errstate(over="ignore", invalid="ignore"):
            h_gamma = np.exp(-(gamma**2) / config.q_gamma)
        line_factors["h_gamma"][alive] = np.where(np.isfinite(gamma), h_gamma, 0.0)
        delta = np.linalg.norm(L.centres[alive] - centroid, axis=1)
        line_factors["h_delta"][alive] = np.exp(-(delta**2) / config.q_delta)
        for name, value in (
            ("alpha_m", np.asarray(alphas, dtype=np.float64)[src]),
            ("beta", np.asarray(betas, dtype=np.float64)[src]),
            ("gamma", gamma),
            ("delta_m", delta),
        ):
            line_measures[name][alive] = value
    names = FACTOR_NAMES[:3] if packed else FACTOR_NAMES
    kept = cands.kept
    cands.measures = {
        name: np.where(kept, np.repeat(value, n_roll), np.nan)
        for name, value in line_measures.items()
    }
    score = np.ones(len(L))
    for name in names:
        score = score * line_factors[name]
    cands.scores = np.where(kept, np.repeat(score, n_roll), np.nan)
    cands.factors = {
        name: np.where(kept, np.repeat(line_factors[name], n_roll), np.nan) for name in names
    }
