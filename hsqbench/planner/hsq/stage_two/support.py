"""The support rule of elimination (rule 2): points at each contact, their plane, unseen contacts.

See :mod:`hsqbench.planner.hsq.stage_two.elimination` for the rule; this module counts what each contact's
support cylinder holds and decides which contacts no camera can see.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet
from hsqbench.planner.hsq.stage_two.line_frame import _chunks, _line_coordinates

#: Query points used to estimate the cloud's spacing (a seeded subset is as good as all).
_SPACING_SAMPLES = 2000


def cloud_spacing(points: NDArray, seed: int = 0) -> float:
    """Median nearest-neighbour distance of the cloud, metres (a seeded subset of queries)."""
    if points.shape[0] < 2:
        return float("inf")
    rng = np.random.default_rng(seed)
    n = min(points.shape[0], _SPACING_SAMPLES)
    query = points[rng.choice(points.shape[0], size=n, replace=False)]
    dist, _ = cKDTree(points).query(query, k=2)
    return float(np.median(dist[:, 1]))


def support_kappa(spacing: float, config: GraspConfig) -> int:
    """Points a supported contact needs: ``max(min_points, fraction * pi r^2 / spacing^2)``."""
    expected = np.pi * config.support_radius_m**2 / max(spacing, 1e-9) ** 2
    return max(int(config.support_min_points), int(np.ceil(config.support_min_fraction * expected)))


@dataclass(frozen=True)
class SupportStats:
    """What the support cylinders at the two contacts of each line hold.

    Attributes:
        counts: (n, 2) cloud points in the cylinder at the ``+d`` and ``-d`` contact.
        cos_tilt: (n, 2) ``|cos|`` of the angle between the line and the normal of the plane
            fitted to those points (smallest principal axis); 0 where fewer than 3 points.
    """

    counts: NDArray[np.int64]
    cos_tilt: NDArray[np.float64]


def support_stats(
    points: NDArray, cands: CandidateSet, lines: NDArray[np.int64], config: GraspConfig
) -> SupportStats:
    """Count the points near each contact of ``lines`` and fit a plane to them."""
    n = lines.size
    counts = np.zeros((n, 2), dtype=np.int64)
    cos_tilt = np.zeros((n, 2))
    L = cands.lines
    r2 = config.support_radius_m**2
    depth = config.contact_depth_m
    for sl in _chunks(n, points.shape[0]):
        idx = lines[sl]
        m = idx.size
        s, u, v = _line_coordinates(points, L.centres[idx], L.directions[idx], L.approach0[idx])
        h = L.half_lengths[idx].astype(np.float32)
        near = (u * u + v * v <= r2) & (np.abs(np.abs(s) - h) <= depth)
        for side, sign in enumerate((1.0, -1.0)):
            flat = np.flatnonzero(near & (sign * s > 0.0))
            ln = flat % m
            coords = np.stack([sign * s.flat[flat], u.flat[flat], v.flat[flat]], axis=1)
            coords = coords.astype(np.float64)
            count = np.bincount(ln, minlength=m)
            counts[sl, side] = count
            # Covariance of each cylinder's points, (m, 3, 3), from per-line sums.
            safe = np.maximum(count, 1)[:, None]
            sums = [np.bincount(ln, weights=coords[:, k], minlength=m) for k in range(3)]
            mean = np.stack(sums, axis=1).astype(np.float64) / safe
            centred = coords - mean[ln]
            cov = np.empty((m, 3, 3))
            for i in range(3):
                for j in range(i, 3):
                    w = centred[:, i] * centred[:, j]
                    cov[:, i, j] = cov[:, j, i] = np.bincount(ln, weights=w, minlength=m)
            _, vectors = np.linalg.eigh(cov)
            cos_tilt[sl, side] = np.where(count >= 3, np.abs(vectors[:, 0, 0]), 0.0)
    return SupportStats(counts, cos_tilt)


def unobservable_contacts(
    cands: CandidateSet,
    lines: NDArray[np.int64],
    cameras: ArrayLike,
    config: GraspConfig,
    support_plane: NDArray | None = None,
) -> NDArray[np.bool_]:
    """(len(lines), 2): whether the ``+d`` / ``-d`` contact of each line faces away from every
    camera, i.e. its modelled normal (``+d`` / ``-d``) is more than ``unseen_incidence_deg``
    from the direction to each camera. Occlusion by other surfaces is not modelled: a contact
    facing a camera counts as observable even if something hides it (the strict choice).

    With a ``support_plane``, a contact facing down (normal more than ``unseen_max_down_deg``
    below the plane's) never counts as unobservable: cameras above a table see no downward face,
    and one without points is as likely the inside of the object (a hidden superquadric fitted
    to the top of a box ends inside it) as its underside."""
    L = cands.lines
    cams = np.asarray(cameras, dtype=np.float64).reshape(-1, 3)
    cos_max = np.cos(np.deg2rad(config.unseen_incidence_deg))
    out = np.empty((lines.size, 2), dtype=bool)
    for side, sign in enumerate((1.0, -1.0)):
        normal = sign * L.directions[lines]
        contact = L.centres[lines] + L.half_lengths[lines, None] * normal
        to_cam = cams[None, :, :] - contact[:, None, :]
        cos = np.einsum("lj,lkj->lk", normal, to_cam) / np.linalg.norm(to_cam, axis=2)
        out[:, side] = np.all(cos < cos_max, axis=1)
        if support_plane is not None:
            down = normal @ np.asarray(support_plane[:3], float)
            out[:, side] &= down >= -np.sin(np.deg2rad(config.unseen_max_down_deg))
    return out
