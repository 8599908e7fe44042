"""Even surface sampling of a superquadric: six face grids, seam thinning and hole filling.

The algorithm is documented on :meth:`hsqbench.superquadric.geometry.Superquadric.sample_surface`, which calls
:func:`_sample_surface` here.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from hsqbench.superquadric.primitives import SurfaceShape, _phi, _quarter_curve

#: Upper bound on the candidate grid nodes of :meth:`Superquadric.sample_surface` (memory guard).
MAX_SAMPLE_NODES = 2_000_000
#: Two samples closer than this fraction of the spacing are thinned to one: seams of the six face
#: grids otherwise give arbitrarily close pairs, and a face grid whose warp does not fit an off-centre
#: part (e.g. the side facets of a square bipyramid) packs rows down to about 0.6 spacing.
_SEAM_MIN_FRACTION = 0.7
#: Close samples are thinned only if their normals differ by less than 120 degrees (cosine above
#: this): a cube edge (90 degrees) still counts, the two sides of a thin plate (180) do not.
_SAME_SIDE_MIN_COS = -0.5
#: Face grids extend past their region while the normal component of their axis is at least this
#: share of the largest one (slope <= 2); those extra nodes are only used to fill holes at seams.
_SEAM_BAND_SHARE = 0.5
#: A spare node fills a hole if no sample lies within this fraction of the spacing; an ideal square
#: grid has no point farther than 0.71 spacing from a node, distorted cells up to about 0.8.
_HOLE_FRACTION = 0.8


def _greedy_thinning(
    points: NDArray,
    normals: NDArray,
    priority: NDArray,
    spare: NDArray[np.bool_],
    min_dist: float,
    spare_dist: float,
) -> NDArray[np.bool_]:
    """Mask of a subset of ``points`` where no two kept points conflict, preferring high priority.

    Two points conflict when closer than ``min_dist``, or ``spare_dist`` if either is flagged
    ``spare``, unless their unit ``normals`` differ by more than 120 degrees: those lie on the two
    sides of a part thinner than the spacing and both must stay. The result is the greedy
    independent set in decreasing priority, computed in parallel rounds: a point beating all its
    remaining conflicting neighbours is kept and those neighbours are dropped. Loops over rounds
    (at most 5 over 100 random shapes), never over points.
    """
    n = points.shape[0]
    keep = np.ones(n, dtype=bool)
    tree = cKDTree(points, balanced_tree=False, compact_nodes=False)  # faster build, same pairs
    pairs = tree.query_pairs(max(min_dist, spare_dist), output_type="ndarray")
    if pairs.size == 0:
        return keep
    i, j = pairs[:, 0], pairs[:, 1]
    dist = np.linalg.norm(points[i] - points[j], axis=1)
    same_side = np.einsum("ij,ij->i", normals[i], normals[j]) > _SAME_SIDE_MIN_COS
    pairs = pairs[same_side & (dist < np.where(spare[i] | spare[j], spare_dist, min_dist))]
    rank = np.empty(n, dtype=np.int64)
    rank[np.argsort(priority, kind="stable")] = np.arange(n)  # ties in index order
    while pairs.size:
        i, j = pairs[:, 0], pairs[:, 1]
        best = np.full(n, -1, dtype=np.int64)
        np.maximum.at(best, i, rank[j])
        np.maximum.at(best, j, rank[i])
        winner = np.zeros(n, dtype=bool)
        involved = np.concatenate([i, j])
        winner[involved] = best[involved] < rank[involved]
        keep[i[winner[j]]] = False
        keep[j[winner[i]]] = False
        settled = ~keep | winner
        pairs = pairs[~(settled[i] | settled[j])]
    return keep


def _face_grid_nodes(
    sq: SurfaceShape, spacing: float
) -> dict[tuple[int, int], NDArray[np.float64]]:
    """Node coordinates along local axis ``m`` for the face grid of ``axis``, keyed ``(m, axis)``.

    Nodes are equal arc-length steps along the central cut of the surface by the plane of ``m``
    and ``axis`` (a quarter superellipse with eps2 in the xy plane, eps1 otherwise), symmetric
    about 0. The step is adjusted so that a whole number of steps spans the quarter: the grid of
    the neighbouring face walks the same cut from the other end and meets this one node for node
    instead of leaving a gap along the seam.
    """
    nodes = {}
    for a, b in ((0, 1), (0, 2), (1, 2)):
        eps = sq.eps2 if (a, b) == (0, 1) else sq.eps1
        c, h, length = _quarter_curve(eps, sq.scale[a], sq.scale[b])
        steps = np.linspace(0.0, length[-1], max(round(length[-1] / spacing), 1) + 1)
        along_a = np.interp(steps, length, c)  # walked from the tip of b
        along_b = np.interp(steps, length, h)[::-1]  # the same nodes walked from the tip of a
        nodes[(a, b)] = np.concatenate([-along_a[:0:-1], along_a])
        nodes[(b, a)] = np.concatenate([-along_b[:0:-1], along_b])
    return nodes


def _face_height(sq: SurfaceShape, axis: int, coords: NDArray) -> tuple[NDArray, NDArray[np.bool_]]:
    """Non-negative coordinate along ``axis`` of the surface above local ``coords`` (N, 3) whose
    ``axis`` column is ignored; second output flags nodes inside the footprint."""
    e1, e2 = sq.eps1, sq.eps2
    q = np.abs(coords) / sq.scale
    if axis == 2:
        hxy = _phi(q[:, 0] ** 2, q[:, 1] ** 2, e2)
        valid = hxy <= 1.0
        height = (1.0 - np.minimum(hxy, 1.0) ** (1.0 / e1)) ** (e1 / 2.0)
    else:
        other = 1 - axis
        w = np.maximum(1.0 - q[:, 2] ** (2.0 / e1), 0.0)
        rest = w ** (e1 / e2) - q[:, other] ** (2.0 / e2)
        valid = rest >= 0.0
        height = np.maximum(rest, 0.0) ** (e2 / 2.0)
    return height * sq.scale[axis], valid


def _face_candidates(
    sq: SurfaceShape, axis: int, nodes_i: NDArray, nodes_j: NDArray
) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Grid nodes of the two faces of ``axis`` (+ and -) lifted onto the surface.

    Returns local points, gradients of rho, a flag for spares (nodes past the own region, used
    only to fill seam holes) and a priority for thinning: ``1 + depth`` into the own region for
    owned nodes, ``share - 1`` for spares, where ``share`` is this axis' normal component over
    the largest one.
    """
    i, j = (m for m in range(3) if m != axis)
    ci, cj = np.meshgrid(nodes_i, nodes_j, indexing="ij")
    p = np.zeros((ci.size, 3))
    p[:, i], p[:, j] = ci.ravel(), cj.ravel()
    p[:, axis], valid = _face_height(sq, axis, p)
    p, grad = p[valid], sq._rho_gradient(p[valid])
    score = np.abs(grad) * sq.scale.max() * (1.0 + 1e-6 * np.abs(p / sq.scale))
    # column by column: numpy reduces rows of three slowly (sum in its order, (s0 + s1) + s2)
    s0, s1, s2 = score.T
    top = np.maximum(np.maximum(s0, s1), s2)
    share = score[:, axis] / top
    owned = share == 1.0
    use = (grad[:, axis] > 0.0) & (share >= _SEAM_BAND_SHARE)
    # depth into the own region: 1 - (second largest score) / (largest)
    second = s0 + s1 + s2 - top - np.minimum(np.minimum(s0, s1), s2)
    priority = np.where(owned, 2.0 - second / top, share - 1.0)
    p, grad, spare, priority = p[use], grad[use], ~owned[use], priority[use]
    # the face on the negative side is the mirror image
    mirror = np.ones(3)
    mirror[axis] = -1.0
    return (
        np.concatenate([p, p * mirror]),
        np.concatenate([grad, grad * mirror]),
        np.tile(spare, 2),
        np.tile(priority, 2),
    )


def _sample_surface(
    sq: SurfaceShape, spacing: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """:meth:`Superquadric.sample_surface` (documented there) for a validated ``spacing``."""
    grid = _face_grid_nodes(sq, spacing)
    nodes = [[grid[(m, axis)] for m in range(3) if m != axis] for axis in range(3)]
    n_nodes = sum(nodes_i.size * nodes_j.size for nodes_i, nodes_j in nodes)
    if n_nodes > MAX_SAMPLE_NODES:
        raise ValueError(
            f"spacing {spacing} m gives {n_nodes} grid nodes for scales {sq.scale} m, more than "
            f"MAX_SAMPLE_NODES={MAX_SAMPLE_NODES}; use a larger spacing"
        )
    faces = [_face_candidates(sq, axis, *nodes[axis]) for axis in range(3)]
    local, grad, spare, priority = (np.concatenate(parts) for parts in zip(*faces, strict=True))
    normals = grad / np.linalg.norm(grad, axis=1, keepdims=True)
    keep = _greedy_thinning(
        local, normals, priority, spare, _SEAM_MIN_FRACTION * spacing, _HOLE_FRACTION * spacing
    )
    local, normals = local[keep], normals[keep]
    local /= np.sqrt(sq.inside_outside_pow(local, local=True))[:, None]
    return sq.to_world(local), normals @ sq.rotation.T
