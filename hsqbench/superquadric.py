"""Superquadric geometry, vectorised and numerically stable.

A superquadric in its own frame is the surface ``F(p) = 1`` of the inside-outside function

    F(x, y, z) = ((|x|/ax)^(2/eps2) + (|y|/ay)^(2/eps2))^(eps2/eps1) + (|z|/az)^(2/eps1)

with shape exponents ``eps1`` (along z) and ``eps2`` (in the xy cross-section), dimensionless, and
semi-axis scales ``ax, ay, az`` in metres. A pose ``(R, t)`` maps local to world: ``p_w = R p + t``.

Powers like ``u^(1/eps)`` overflow for small eps, so F is evaluated through

    phi(u, v, t) = max(u, v) * (1 + (min(u, v) / max(u, v))^(1/t))^t,

which gives ``G = F^eps1 = phi(phi(x²/ax², y²/ay², eps2), z²/az², eps1)`` without any large
intermediate. G is homogeneous of degree 2 in p, so the surface radius along a direction n is
``1 / sqrt(G(n))`` and the radial distance is ``| |p| - |p| / sqrt(G(p)) |``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

#: Shape exponents are kept within these bounds everywhere (dimensionless).
EPS_MIN = 0.05
EPS_MAX = 2.0
#: Largest finite F returned; beyond this a point is "infinitely" outside.
_LOG_F_MAX = 700.0

#: Upper bound on the candidate grid nodes of :meth:`Superquadric.sample_surface` (memory guard).
MAX_SAMPLE_NODES = 2_000_000
#: Vertices per quarter curve of the fine polylines used to reparametrise superellipses by arc length;
#: 1024 keeps chord errors far below any sampling spacing, even for eps = 0.05 corners.
_CURVE_FINE = 1024
#: Two samples closer than this fraction of the spacing are thinned to one: seams of the six face
#: grids otherwise give arbitrarily close pairs, and a face grid whose warp does not fit an off-centre
#: part (e.g. the side facets of a square bipyramid) packs rows down to about 0.6 spacing.
_SEAM_MIN_FRACTION = 0.7
#: Face grids extend past their region while the normal component of their axis is at least this
#: share of the largest one (slope <= 2); those extra nodes are only used to fill holes at seams.
_SEAM_BAND_SHARE = 0.5
#: A spare node fills a hole if no sample lies within this fraction of the spacing; an ideal square
#: grid has no point farther than 0.71 spacing from a node, distorted cells up to about 0.8.
_HOLE_FRACTION = 0.8

#: Length of the flat parameter vector: eps1, eps2, ax, ay, az, rotation vector (3), translation (3).
N_PARAMS = 11


def _phi(u: NDArray, v: NDArray, t: float | NDArray) -> NDArray:
    """``(u^(1/t) + v^(1/t))^t`` for u, v >= 0 without overflow or underflow."""
    hi = np.maximum(u, v)
    lo = np.minimum(u, v)
    safe_hi = np.where(hi > 0.0, hi, 1.0)
    ratio = lo / safe_hi
    out = hi * (1.0 + ratio ** (1.0 / t)) ** t
    return np.where(hi > 0.0, out, 0.0)


def _phi_ratios(u: NDArray, v: NDArray, t: float) -> tuple[NDArray, NDArray, NDArray]:
    """``phi(u, v, t)`` with the ratios ``u / phi`` and ``v / phi`` (in [0, 1]; 0 where phi = 0)."""
    hi = np.maximum(u, v)
    lo = np.minimum(u, v)
    pos = hi > 0.0
    rho = lo / np.where(pos, hi, 1.0)
    r_hi = np.where(pos, (1.0 + rho ** (1.0 / t)) ** (-t), 0.0)
    r_lo = rho * r_hi
    value = np.where(pos, hi / np.where(pos, r_hi, 1.0), 0.0)
    u_is_hi = u >= v
    return value, np.where(u_is_hi, r_hi, r_lo), np.where(u_is_hi, r_lo, r_hi)


def _quarter_curve(eps: float, a: float, b: float) -> tuple[NDArray, NDArray, NDArray]:
    """Fine polyline of the quarter superellipse ``(c/a)^(2/eps) + (h/b)^(2/eps) = 1``.

    Runs from ``(0, b)`` to ``(a, 0)``; returns ``c`` (increasing), ``h`` and the arc length from
    ``(0, b)``, metres. Vertices are spread by the polar angle, which resolves both the flat parts
    and the rounded corners of small-eps curves.
    """
    theta = np.linspace(0.5 * np.pi, 0.0, _CURVE_FINE)
    cos, sin = np.cos(theta), np.sin(theta)
    cos[0], sin[-1] = 0.0, 0.0
    radius = 1.0 / np.sqrt(_phi((cos / a) ** 2, (sin / b) ** 2, eps))
    c, h = radius * cos, radius * sin
    length = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(c), np.diff(h)))])
    return c, h, length


def _greedy_thinning(
    points: NDArray, priority: NDArray, spare: NDArray[np.bool_], min_dist: float, spare_dist: float
) -> NDArray[np.bool_]:
    """Mask of a subset of ``points`` where no two kept points conflict, preferring high priority.

    Two points conflict when closer than ``min_dist``, or ``spare_dist`` if either is flagged
    ``spare``. The result is the greedy independent set in decreasing priority, computed in
    parallel rounds: a point beating all its remaining conflicting neighbours is kept and those
    neighbours are dropped. Loops over rounds (a handful), never over points.
    """
    n = points.shape[0]
    keep = np.ones(n, dtype=bool)
    pairs = cKDTree(points).query_pairs(max(min_dist, spare_dist), output_type="ndarray")
    if pairs.size == 0:
        return keep
    dist = np.linalg.norm(points[pairs[:, 0]] - points[pairs[:, 1]], axis=1)
    pairs = pairs[dist < np.where(spare[pairs[:, 0]] | spare[pairs[:, 1]], spare_dist, min_dist)]
    rank = np.empty(n, dtype=np.int64)
    rank[np.lexsort((np.arange(n), priority))] = np.arange(n)
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


def as_points(points: ArrayLike, name: str = "points") -> NDArray[np.float64]:
    """Validate and return an (N, 3) float64 array."""
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == 3:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got {arr.shape}")
    return arr


@dataclass
class Superquadric:
    """One superquadric with a pose in the world frame.

    Attributes:
        eps1: shape exponent along the local z axis, in [EPS_MIN, EPS_MAX].
        eps2: shape exponent of the xy cross-section, in [EPS_MIN, EPS_MAX].
        scale: semi-axes (ax, ay, az) in metres, all > 0.
        rotation: 3x3 rotation matrix, local to world; its columns are the local axes in the world.
        translation: centre in the world frame, metres.
    """

    eps1: float
    eps2: float
    scale: NDArray[np.float64]
    rotation: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    translation: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        self.eps1 = float(self.eps1)
        self.eps2 = float(self.eps2)
        self.scale = np.asarray(self.scale, dtype=np.float64).reshape(3)
        self.rotation = np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)
        self.translation = np.asarray(self.translation, dtype=np.float64).reshape(3)
        values = np.concatenate(
            [[self.eps1, self.eps2], self.scale, self.rotation.ravel(), self.translation]
        )
        if not np.all(np.isfinite(values)):
            raise ValueError(f"superquadric parameters must be finite, got {self!r}")
        if not (
            EPS_MIN - 1e-9 <= self.eps1 <= EPS_MAX + 1e-9
            and EPS_MIN - 1e-9 <= self.eps2 <= EPS_MAX + 1e-9
        ):
            raise ValueError(
                f"eps1, eps2 must lie in [{EPS_MIN}, {EPS_MAX}], got {self.eps1}, {self.eps2}"
            )
        if np.any(self.scale <= 0):
            raise ValueError(f"scales must be positive metres, got {self.scale}")
        if (
            not np.allclose(self.rotation.T @ self.rotation, np.eye(3), atol=1e-6)
            or np.linalg.det(self.rotation) < 0
        ):
            raise ValueError("rotation must be a proper rotation matrix (orthonormal, det +1)")

    # ----------------------------------------------------------------- frames and parameters
    def to_local(self, points: ArrayLike) -> NDArray[np.float64]:
        """World points (N, 3) -> local frame: ``R^T (p - t)``."""
        return (as_points(points) - self.translation) @ self.rotation

    def to_world(self, points: ArrayLike) -> NDArray[np.float64]:
        """Local points (N, 3) -> world frame: ``R p + t``."""
        return as_points(points) @ self.rotation.T + self.translation

    def to_vector(self) -> NDArray[np.float64]:
        """Flat parameters ``[eps1, eps2, ax, ay, az, rx, ry, rz, tx, ty, tz]`` (rotation vector in rad)."""
        rotvec = Rotation.from_matrix(self.rotation).as_rotvec()
        return np.concatenate([[self.eps1, self.eps2], self.scale, rotvec, self.translation])

    @classmethod
    def from_vector(cls, params: ArrayLike) -> Superquadric:
        """Inverse of :meth:`to_vector`."""
        p = np.asarray(params, dtype=np.float64).reshape(N_PARAMS)
        rotation = Rotation.from_rotvec(p[5:8]).as_matrix()
        return cls(p[0], p[1], p[2:5], rotation, p[8:11])

    # ----------------------------------------------------------------- implicit function
    def inside_outside_pow(self, points: ArrayLike, local: bool = False) -> NDArray[np.float64]:
        """``G = F^eps1``, finite everywhere; < 1 inside, 1 on the surface, > 1 outside."""
        p = as_points(points) if local else self.to_local(points)
        sq = (p / self.scale) ** 2
        return _phi(_phi(sq[:, 0], sq[:, 1], self.eps2), sq[:, 2], self.eps1)

    def inside_outside(self, points: ArrayLike) -> NDArray[np.float64]:
        """F at world points (N,); clipped to a large finite value far outside."""
        g = self.inside_outside_pow(points)
        with np.errstate(divide="ignore"):
            log_f = np.log(g) / self.eps1
        return np.exp(np.clip(log_f, -_LOG_F_MAX, _LOG_F_MAX))

    def surface_radius(self, directions: ArrayLike, local: bool = False) -> NDArray[np.float64]:
        """Distance from the centre to the surface along each direction (N,), metres."""
        d = as_points(directions, "directions")
        if not local:
            d = d @ self.rotation
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        n = d / np.where(norm > 0, norm, 1.0)
        n[norm[:, 0] == 0] = (0.0, 0.0, 1.0)
        return 1.0 / np.sqrt(self.inside_outside_pow(n, local=True))

    def radial_distance(self, points: ArrayLike) -> NDArray[np.float64]:
        """``|p - c| * |1 - F^(-eps1/2)|``: distance to the surface along the ray from the centre (N,), m.

        At the centre itself the ray is undefined; the smallest semi-axis is returned there.
        """
        local = self.to_local(points)
        r = np.linalg.norm(local, axis=1)
        radius = self.surface_radius(local, local=True)
        return np.where(r > 0, np.abs(r - radius), np.min(self.scale))

    def _rho_gradient(self, local: NDArray) -> NDArray[np.float64]:
        """Gradient (N, 3), 1/m, of ``rho = sqrt(G)`` at local points; never NaN.

        ``rho`` is the nested lp norm ``|| (||(x/ax, y/ay)||_(2/eps2), z/az) ||_(2/eps1)``, homogeneous
        of degree 1. With ``X = x^2/ax^2`` (likewise Y, Z), ``H = phi(X, Y, eps2)`` and ``G = phi(H, Z,
        eps1)``, its components are ``sign(x)/ax (H/G)^(1/eps1 - 1/2) (X/H)^(1/eps2 - 1/2)``, the same
        for y, and ``sign(z)/az (Z/G)^(1/eps1 - 1/2)``: ratios in [0, 1] raised to non-negative powers.
        """
        sq = (local / self.scale) ** 2
        h, r_x, r_y = _phi_ratios(sq[:, 0], sq[:, 1], self.eps2)
        _, r_h, r_z = _phi_ratios(h, sq[:, 2], self.eps1)
        a1 = max(1.0 / self.eps1 - 0.5, 0.0)
        a2 = max(1.0 / self.eps2 - 0.5, 0.0)
        f_h = r_h**a1
        factors = np.stack([f_h * r_x**a2, f_h * r_y**a2, r_z**a1], axis=1)
        return np.sign(local) / self.scale * factors

    def normals(self, points: ArrayLike) -> NDArray[np.float64]:
        """Unit outward normals (N, 3) in the world frame: the normalised gradient of G.

        At the centre, where the gradient vanishes, +z of the local frame is returned.
        """
        local = self.to_local(points)
        grad = self._rho_gradient(local)
        norm = np.linalg.norm(grad, axis=1, keepdims=True)
        unit = np.where(norm > 0, grad / np.where(norm > 0, norm, 1.0), (0.0, 0.0, 1.0))
        return unit @ self.rotation.T

    # ----------------------------------------------------------------- surface sampling
    def _face_grid_nodes(self, spacing: float) -> dict[tuple[int, int], NDArray[np.float64]]:
        """Node coordinates along local axis ``m`` for the face grid of ``axis``, keyed ``(m, axis)``.

        Nodes are equal arc-length steps along the central cut of the surface by the plane of ``m``
        and ``axis`` (a quarter superellipse with eps2 in the xy plane, eps1 otherwise), symmetric
        about 0. The step is adjusted so that a whole number of steps spans the quarter: the grid of
        the neighbouring face walks the same cut from the other end and meets this one node for node
        instead of leaving a gap along the seam.
        """
        nodes = {}
        for a, b in ((0, 1), (0, 2), (1, 2)):
            eps = self.eps2 if (a, b) == (0, 1) else self.eps1
            c, h, length = _quarter_curve(eps, self.scale[a], self.scale[b])
            steps = np.linspace(0.0, length[-1], max(round(length[-1] / spacing), 1) + 1)
            along_a = np.interp(steps, length, c)  # walked from the tip of b
            along_b = np.interp(steps, length, h)[::-1]  # the same nodes walked from the tip of a
            nodes[(a, b)] = np.concatenate([-along_a[:0:-1], along_a])
            nodes[(b, a)] = np.concatenate([-along_b[:0:-1], along_b])
        return nodes

    def _face_height(self, axis: int, coords: NDArray) -> tuple[NDArray, NDArray[np.bool_]]:
        """Non-negative coordinate along ``axis`` of the surface above local ``coords`` (N, 3) whose
        ``axis`` column is ignored; second output flags nodes inside the footprint."""
        e1, e2 = self.eps1, self.eps2
        q = np.abs(coords) / self.scale
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
        return height * self.scale[axis], valid

    def _face_candidates(
        self, axis: int, nodes_i: NDArray, nodes_j: NDArray
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
        p[:, axis], valid = self._face_height(axis, p)
        p, grad = p[valid], self._rho_gradient(p[valid])
        score = np.abs(grad) * self.scale.max() * (1.0 + 1e-6 * np.abs(p / self.scale))
        top = score.max(axis=1)
        share = score[:, axis] / top
        owned = share == 1.0
        use = (grad[:, axis] > 0.0) & (share >= _SEAM_BAND_SHARE)
        # depth into the own region: 1 - (second largest score) / (largest)
        second = score.sum(axis=1) - top - score.min(axis=1)
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

    def sample_surface(self, spacing: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Even sampling of the surface at about ``spacing`` metres between neighbours.

        The surface is split into six regions (faces) by the dominant component of the normal in
        the local frame, ties broken by the dominant scaled coordinate. Each face is a graph over the
        plane of the two other axes with slope at most 1, sampled on a grid whose lines follow equal
        arc-length steps of the two central cuts (superellipses with eps1 or eps2), so flat faces,
        rounded edges and pinched tips all get the same spacing. Samples closer than ``0.7 *
        spacing`` (along the seams, or where a warp fits an off-centre part poorly) are thinned to
        one, preferring nodes deep inside their face, and holes wider than ``0.8 * spacing`` along
        the seams are filled with nodes of the neighbouring face grid that extend past the seam.
        Points satisfy ``G = 1`` to rounding (each is finally projected radially onto the surface).

        Measured over 300 random shapes (eps in [0.05, 2], semi-axes 1-8 cm, spacing 2-5 mm): the
        mean nearest-neighbour distance is 0.83-1.03 ``spacing`` with a coefficient of variation of
        at most 0.14, and no surface point is farther than 1.03 ``spacing`` from a sample (0.9 for
        spheres, boxes, cylinders and octahedra).

        Args:
            spacing: target distance between neighbouring samples, metres (> 0).

        Returns:
            ``(points, normals)``, both (N, 3) in the world frame; normals are unit and outward.

        Raises:
            ValueError: if ``spacing`` is not a positive finite number or the grids would exceed
                :data:`MAX_SAMPLE_NODES` nodes (pick a larger spacing).
        """
        spacing = float(spacing)
        if not (np.isfinite(spacing) and spacing > 0.0):
            raise ValueError(f"spacing must be a positive number of metres, got {spacing}")
        grid = self._face_grid_nodes(spacing)
        nodes = [[grid[(m, axis)] for m in range(3) if m != axis] for axis in range(3)]
        n_nodes = sum(nodes_i.size * nodes_j.size for nodes_i, nodes_j in nodes)
        if n_nodes > MAX_SAMPLE_NODES:
            raise ValueError(
                f"spacing {spacing} m gives {n_nodes} grid nodes for scales {self.scale} m, more than "
                f"MAX_SAMPLE_NODES={MAX_SAMPLE_NODES}; use a larger spacing"
            )
        faces = [self._face_candidates(axis, *nodes[axis]) for axis in range(3)]
        local, grad, spare, priority = (np.concatenate(parts) for parts in zip(*faces, strict=True))
        keep = _greedy_thinning(
            local, priority, spare, _SEAM_MIN_FRACTION * spacing, _HOLE_FRACTION * spacing
        )
        local, grad = local[keep], grad[keep]
        local /= np.sqrt(self.inside_outside_pow(local, local=True))[:, None]
        normals = grad / np.linalg.norm(grad, axis=1, keepdims=True)
        return self.to_world(local), normals @ self.rotation.T


# --------------------------------------------------------------------- fit measures of the planner
def _check_fit_inputs(points: ArrayLike, spacing: float) -> NDArray[np.float64]:
    cloud = as_points(points)
    if cloud.shape[0] == 0:
        raise ValueError("the point cloud is empty; alpha and beta need at least one point")
    if not np.all(np.isfinite(cloud)):
        raise ValueError("the point cloud contains NaN or inf coordinates")
    return cloud


def alpha_beta(
    points: ArrayLike, sq: Superquadric, spacing: float, d_th: float
) -> tuple[float, float]:
    """Both fit measures of the paper from one surface sampling: ``(alpha, beta)``.

    ``S`` is :meth:`Superquadric.sample_surface` at ``spacing``; see :func:`point_to_surface_alpha`
    and :func:`coverage_beta` for the definitions. Metres throughout.
    """
    cloud = _check_fit_inputs(points, spacing)
    d_th = float(d_th)
    if not (np.isfinite(d_th) and d_th > 0.0):
        raise ValueError(f"d_th must be a positive number of metres, got {d_th}")
    samples, _ = sq.sample_surface(spacing)
    alpha = float(np.mean(cKDTree(samples).query(cloud)[0]))
    near = cKDTree(cloud).query(samples, distance_upper_bound=d_th)[0]
    beta = float(np.count_nonzero(np.isfinite(near)) / samples.shape[0])
    return alpha, beta


def point_to_surface_alpha(points: ArrayLike, sq: Superquadric, spacing: float) -> float:
    """``alpha = mean_i min_j ||y_i - s_j||``, metres: mean distance from the cloud Y to a dense even
    sampling S of the surface at ``spacing``.

    Discretisation bias: a point lying exactly on the surface is on average about ``0.4 * spacing``
    from the nearest sample and at most about ``0.7 * spacing`` (half the diagonal of a grid cell),
    so alpha over-estimates the true mean distance by at most about ``spacing / 2`` on average; use a
    spacing well below the distances you want to resolve (2 mm for cm-level fits).

    Raises:
        ValueError: on an empty or non-finite cloud or a bad spacing.
    """
    cloud = _check_fit_inputs(points, spacing)
    samples, _ = sq.sample_surface(spacing)
    return float(np.mean(cKDTree(samples).query(cloud)[0]))


def coverage_beta(points: ArrayLike, sq: Superquadric, spacing: float, d_th: float) -> float:
    """``beta = |T| / |S|``: fraction of the surface samples S (at ``spacing``) that have a cloud point
    within ``d_th`` metres.

    ``d_th`` must bridge the gaps between cloud points on the surface plus the sampling offset: a
    sensible default is ``d_th = 2 * max(spacing, cloud point spacing)``, e.g. 5 mm for a 2 mm sampling
    of a cloud with about 2.5 mm between points. Too small a ``d_th`` reports holes that are only
    gaps between cloud points.

    Raises:
        ValueError: on an empty or non-finite cloud, a bad spacing or a non-positive ``d_th``.
    """
    return alpha_beta(points, sq, spacing, d_th)[1]
