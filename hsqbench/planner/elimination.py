"""Candidate elimination (paper, stage two), plus the table and the hand's path.

All rules look at the cloud voxel-downsampled at ``elimination_voxel_m`` (one centroid per
occupied voxel): the cost then follows the object's surface area, not the sensor's density, and
the centroids average out part of the noise. Rules, in order; a candidate carries the first rule
that removed it (``CandidateSet.rejected_by``):

0. ``duplicate`` (addition): several seeds of stage one often converge to the same part, so the
   same closing line comes from several hidden superquadrics. A line within
   ``duplicate_distance_m`` (centre and half length) and ``duplicate_angle_deg`` (direction) of a
   line from a better-fitting superquadric (higher ``h_alpha h_beta``) goes: the ranking then
   holds each pose once, and the rules below run on fewer lines.
1. ``width``: the contacts are farther apart than the opening allows,
   ``2 h > l_w - opening_margin_m``.
2. ``support`` (paper): a cylinder of radius ``support_radius_m`` around each contact, reaching
   ``contact_depth_m`` both ways along the line (but not past ``P_G``), must hold at least
   ``kappa`` cloud points, else every roll of the line goes. ``kappa`` is the larger of
   ``support_min_points`` and ``support_min_fraction`` of the points a fully seen disc of that
   radius holds at the (downsampled) cloud's spacing (median nearest-neighbour distance), so one
   setting serves dense and sparse clouds. Addition: the points must also form a surface the
   finger can push on, i.e. the normal of the plane fitted to them must be within
   ``support_max_tilt_deg`` of the line. This removes lines whose contact is an edge of the
   object (e.g. a superquadric fitted to one face of a box, gripped across that face's length).
   Addition, when the cameras' positions are known: a contact that no camera can see (its
   modelled normal more than ``unseen_incidence_deg`` from the direction to every camera, e.g.
   the face of an object toward the robot, which neither side camera sees) cannot show support,
   so it is not asked to; the other contact must show it. Without this, every line needing that
   face goes, whatever the object. Downward faces are excluded (``unseen_max_down_deg``): from
   above they are never seen, and a hidden superquadric fitted to the top of a body ends in a
   downward face inside it.
The gripper approaches open to ``min(l_w, 2 h + 2 contact_depth_m)`` (``approach_openings``,
kept as ``ClosingLines.openings`` and ``Grasp.approach_width``): its fingers then clear the contact
surface (noise and fit error included) and close only through it, so the open fingers are the
whole finger volume to check, and no wider opening reaches into neighbours or the table.

3. ``table``: with a support plane ``a x + b y + c z + d = 0`` (unit normal toward the free side),
   a pose whose fingers or palm (palm swept back by ``approach_distance_m``) come closer than
   ``table_clearance_m`` to the plane, or cross it, goes.
4. ``collision`` (paper): a cylinder of radius ``l_j`` and half-height ``min(h, l_w / 2)`` about
   the line; cloud points between its end planes but outside it are obstacles, and a pose whose
   gripper body (two open fingers and the palm) holds any of them goes (more than
   ``max_obstacle_points`` of them: 0, the paper's rule, by default).
5. ``sweep`` (addition, ``sweep_rule``): the paper only looks between the end planes. Any cloud point in the
   volume the hand sweeps also removes the pose: the open fingers, and the palm swept back by
   ``approach_distance_m`` (the straight-line approach from the pre-grasp pose). E.g. the body of
   a mug beside a finger that grips its handle.

Rules 4 and 5 are exact for the box model of the gripper and cost O(lines x points), not
O(candidates x points): in the frame of a line (``s`` along it, polar ``r, theta`` about it) a
point is inside a box at roll ``phi`` iff ``s`` is within the box's extent along the closing axis
and ``psi = theta - phi`` satisfies ``r cos(psi) in [z_lo, z_hi]`` and ``|r sin(psi)| <= y_half``:
at most four arcs of ``phi``, which mark the discrete rolls they contain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from hsqbench.planner.candidates import (
    KEPT,
    REJECTION_REASONS,
    CandidateSet,
    ClosingLines,
    roll_frames,
)
from hsqbench.planner.config import GraspConfig
from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.gripper import GripperModel

#: One line per rule, for messages and the viewer's legend.
RULE_DESCRIPTIONS = {
    "duplicate": "the same closing line from a better-fitting hidden superquadric",
    "width": "contacts farther apart than the gripper opens",
    "support": "too few cloud points at a contact, or no surface there facing the finger",
    "table": "fingers or palm would enter the support plane",
    "collision": "paper's test: object points outside the jaw's reach between the fingers",
    "sweep": "a cloud point in the open fingers or in the palm's approach path",
}

#: Line-by-point pairs processed at once: a dozen float32 arrays of this size stay in cache.
_CHUNK_PAIRS = 100_000
#: Query points used to estimate the cloud's spacing (a seeded subset is as good as all).
_SPACING_SAMPLES = 2000
#: Slack, in roll steps, when deciding whether a discrete roll lies in an arc (favours collision;
#: covers the float32 rounding of the angles, about 1e-7 rad).
_ARC_SLACK = 1e-5
#: An interval of |psi| that ends within this of 0 or pi (radians, float32 rounding) reaches it.
_ANGLE_TOL = 1e-6


@dataclass(frozen=True)
class EliminationReport:
    """What elimination did.

    Attributes:
        remaining: candidates left after each rule, in order, starting with ``synthesised``.
        kappa: the support threshold used (points of the downsampled cloud).
        spacing_m: the downsampled cloud's median nearest-neighbour distance used for ``kappa``.
        n_points: points of the downsampled cloud the rules were checked against.
    """

    remaining: dict[str, int]
    kappa: int
    spacing_m: float
    n_points: int


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


def _line_coordinates(
    points: NDArray, centres: NDArray, directions: NDArray, approach0: NDArray
) -> tuple[NDArray, NDArray, NDArray]:
    """Points in each line's frame: ``s`` along ``d``, ``u`` along ``e1``, ``v`` along ``e2``; (M, L).

    float32, relative to each line's centre (so a few micrometres at most are lost, far below
    the cloud's noise) and half the memory traffic of float64. Written as broadcast sums, not
    ``points @ axes.T``: a (M, 3) x (3, L) product is too skinny for BLAS, whose threads only
    add overhead on a busy machine.
    """
    e2 = np.cross(directions, approach0)
    rel = [points[:, k, None].astype(np.float32) for k in range(3)]

    def project(axes: NDArray) -> NDArray:
        offset = np.einsum("ij,ij->i", centres, axes).astype(np.float32)
        a = axes.astype(np.float32)
        return rel[0] * a[:, 0] + rel[1] * a[:, 1] + rel[2] * a[:, 2] - offset

    return project(directions), project(approach0), project(e2)


def _chunks(n_lines: int, n_points: int):
    size = max(1, _CHUNK_PAIRS // max(n_points, 1))
    for start in range(0, n_lines, size):
        yield slice(start, min(start + size, n_lines))


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


def duplicate_lines(
    lines: ClosingLines, priority: NDArray, config: GraspConfig
) -> NDArray[np.bool_]:
    """(L,): lines within tolerance of a line of higher ``priority`` (ties: lower index wins).

    Lines are compared as points ``(centre / tol_m, d / tol_rad, h / tol_m)`` with the sign of
    ``d`` fixed (a line has no direction); pairs within distance 1 are duplicates. A line with a
    better neighbour goes even if that neighbour is itself a duplicate of a third, so a chain of
    near-equal lines keeps its best member.
    """
    n = len(lines)
    if n < 2:
        return np.zeros(n, dtype=bool)
    d = lines.directions
    first = np.argmax(np.abs(d) > 1e-9, axis=1)
    d = d * np.sign(d[np.arange(n), first])[:, None]
    tol_m, tol_rad = config.duplicate_distance_m, np.deg2rad(config.duplicate_angle_deg)
    key = np.column_stack([lines.centres / tol_m, d / tol_rad, lines.half_lengths / tol_m])
    pairs = cKDTree(key).query_pairs(1.0, output_type="ndarray")
    dup = np.zeros(n, dtype=bool)
    if pairs.size:
        i, j = pairs[:, 0], pairs[:, 1]  # i < j
        j_better = priority[j] > priority[i]
        dup[np.where(j_better, i, j)] = True
    return dup


def approach_openings(
    half_lengths: NDArray, gripper: GripperModel, config: GraspConfig
) -> NDArray[np.float64]:
    """Opening of the gripper on approach for each line, metres: the contacts plus
    ``contact_depth_m`` on each side (the fingers then clear the contact surface, noise and fit
    error included, and close only through it), at most ``l_w``."""
    return np.minimum(2.0 * (half_lengths + config.contact_depth_m), gripper.max_opening_m)


def line_boxes(
    gripper: GripperModel, openings: NDArray, palm_extension_m: float = 0.0
) -> NDArray[np.float64]:
    """The gripper's boxes for each line's opening, grasp frame: (n, 3, 2, 3), see
    :meth:`GripperModel.boxes` (``[finger+x, finger-x, palm]``, each ``[lower, upper]``)."""
    base = gripper.boxes(palm_extension_m=palm_extension_m)
    boxes = np.broadcast_to(base, (openings.size, *base.shape)).copy()
    half = 0.5 * openings
    boxes[:, 0, 0, 0], boxes[:, 0, 1, 0] = half, half + gripper.finger_thickness_m
    boxes[:, 1, 0, 0], boxes[:, 1, 1, 0] = -half - gripper.finger_thickness_m, -half
    return boxes


def table_clear(
    cands: CandidateSet,
    lines: NDArray[np.int64],
    boxes: NDArray,
    plane: NDArray,
    clearance: float,
) -> NDArray[np.bool_]:
    """(len(lines), R): each line's ``boxes`` (n, 3, 2, 3) stay ``clearance`` metres on the free
    side of ``plane`` at every roll (a box is on one side iff its 8 corners are)."""
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    # Corners (n, 24, 3): box b, corner c takes coordinate k from boxes[:, b, pick[c, k], k].
    corners = boxes[:, :, pick, np.arange(3)].reshape(lines.size, 8 * boxes.shape[1], 3)
    L = cands.lines
    frames = roll_frames(L.directions[lines], L.approach0[lines], cands.roll_angles)
    normal, offset = plane[:3], plane[3]
    # n . (P_G + R c) + d for every corner: (lines, R, 24).
    base = L.centres[lines] @ normal + offset
    along = np.einsum("k,lrkj->lrj", normal, frames)
    dist = base[:, None, None] + np.einsum("lrj,lcj->lrc", along, corners)
    return np.all(dist >= clearance, axis=2)


def _mark_arcs(
    r: NDArray,
    theta: NDArray,
    line: NDArray[np.int64],
    box: NDArray,
    n_roll: int,
    diff: NDArray,
) -> None:
    """Add +1/-1 markers to ``diff`` (n_lines, 4 n_roll + 1; roll ``j`` at column ``j + 2
    n_roll``) for the rolls at which each point, at distance ``r`` and angle ``theta`` about its
    line and within ``box``'s extent along the line, lies inside ``box`` (grasp frame,
    symmetric in y).

    The point is inside at roll ``phi`` iff ``psi = theta - phi`` has ``r cos(psi)`` in
    ``[z_lo, z_hi]`` (``|psi|`` in ``[a_lo, a_hi]``) and ``|r sin(psi)| <= y_half`` (``|psi|``
    in ``[0, beta]`` or ``[pi - beta, pi]``): one or two intervals of ``|psi|``, each two arcs of
    ``phi`` that merge into one when the interval reaches 0 or pi.
    """
    # Python floats: they keep float32 arrays float32 (a numpy float64 scalar would not).
    z_lo, y_hi, z_hi = float(box[0, 2]), float(box[1, 1]), float(box[1, 2])
    rs = np.maximum(r, 1e-12)
    reach = (z_lo <= rs) & (z_hi >= -rs)
    a_lo = np.arccos(np.clip(z_hi / rs, -1.0, 1.0))
    a_hi = np.arccos(np.clip(z_lo / rs, -1.0, 1.0))
    beta = np.arcsin(np.clip(y_hi / rs, 0.0, 1.0))
    intervals = []
    if z_hi > 0.0:  # else a_lo > pi/2 >= beta: the first interval is empty
        intervals.append((a_lo, np.minimum(a_hi, beta)))
    if z_lo < 0.0:  # else a_hi < pi/2 <= pi - beta: the second is empty
        intervals.append((np.maximum(a_lo, np.pi - beta), a_hi))
    if len(intervals) == 2:
        # Intervals that meet (a point within y_half of the line at every angle) are one: the
        # rolls at their junction are then marked once, so the markers count points.
        (lo1, hi1), (lo2, hi2) = intervals
        meet = (lo1 <= hi1) & (lo2 <= hi2) & (hi1 >= lo2 - _ANGLE_TOL)
        intervals = [(lo1, np.where(meet, hi2, hi1)), (np.where(meet, np.inf, lo2), hi2)]
    step = 2.0 * np.pi / n_roll
    width = diff.shape[1]
    first, last = [], []
    for lo, hi in intervals:
        ok = reach & (lo <= hi)
        at_zero, at_pi = lo[ok] <= _ANGLE_TOL, hi[ok] >= np.pi - _ANGLE_TOL
        kinds = (at_zero & at_pi, at_zero & ~at_pi, ~at_zero & at_pi, ~at_zero & ~at_pi)
        for kind, use in enumerate(kinds):
            if not np.any(use):
                continue
            where = np.flatnonzero(ok)[use]
            t, p, q = theta[where], lo[where], hi[where]
            base = line[where] * width + 2 * n_roll
            # phi = theta - psi for psi in [p, q] and [-q, -p]; arcs that meet merge.
            if kind == 0:
                arcs = [(t - np.pi, t + np.pi)]
            elif kind == 1:
                arcs = [(t - q, t + q)]
            elif kind == 2:
                arcs = [(t + p - 2.0 * np.pi, t - p)]
            else:
                arcs = [(t - q, t - p), (t + p, t + q)]
            for start, stop in arcs:
                j_lo = np.ceil(start / step - _ARC_SLACK).astype(np.int64)
                j_hi = np.floor(stop / step + _ARC_SLACK).astype(np.int64)
                # A full circle ends where it starts: each roll once.
                j_hi = np.minimum(j_hi, j_lo + n_roll - 1)
                valid = j_lo <= j_hi
                first.append(base[valid] + j_lo[valid])
                last.append(base[valid] + j_hi[valid] + 1)
    if first:
        starts = np.bincount(np.concatenate(first), minlength=diff.size)
        stops = np.bincount(np.concatenate(last), minlength=diff.size)
        diff += (starts - stops).reshape(diff.shape)


def body_hits(
    points: NDArray,
    cands: CandidateSet,
    lines: NDArray[np.int64],
    boxes: NDArray,
    obstacle_radius: NDArray | None = None,
    obstacle_half_height: NDArray | None = None,
    max_points: int = 0,
) -> NDArray[np.bool_]:
    """(len(lines), R): whether more than ``max_points`` obstacle points lie inside each line's
    ``boxes``
    (n, k, 2, 3), grasp frame, at each roll.

    The boxes' extents across the closing axis (y, z) must be the same for every line and
    symmetric in y; their extents along it may differ (the fingers follow each line's opening).
    Obstacles are all ``points``, or, when ``obstacle_radius`` and ``obstacle_half_height`` (per
    line) are given, only the points with ``|s| <= half_height`` and ``r > radius`` (the paper's
    collision cylinder).
    """
    if not (
        np.allclose(boxes[:, :, :, 1:], boxes[:1, :, :, 1:])
        and np.allclose(boxes[:, :, 0, 1], -boxes[:, :, 1, 1])
    ):
        raise ValueError("box cross-sections must be shared by all lines and symmetric in y")
    n_roll = cands.n_roll
    out = np.zeros((lines.size, n_roll), dtype=bool)
    if lines.size == 0 or points.shape[0] == 0:
        return out
    L = cands.lines
    for sl in _chunks(lines.size, points.shape[0]):
        idx = lines[sl]
        n = idx.size
        s, u, v = _line_coordinates(points, L.centres[idx], L.directions[idx], L.approach0[idx])
        r2 = u * u + v * v
        obstacle = None
        if obstacle_radius is not None:
            obstacle = np.abs(s) <= obstacle_half_height[sl].astype(np.float32)
            obstacle &= r2 > (obstacle_radius[sl] ** 2).astype(np.float32)
        diff = np.zeros((n, 4 * n_roll + 1), dtype=np.int64)
        chunk_boxes = boxes[sl].astype(np.float32)
        for b in range(boxes.shape[1]):
            (_, _, z_lo), (_, y_hi, z_hi) = boxes[0, b]
            # The box's distance range from the line bounds r: a cheap filter before any
            # trigonometry.
            r_min = max(z_lo, -z_hi, 0.0)
            r_max2 = max(z_lo**2, z_hi**2) + y_hi**2
            mask = (s >= chunk_boxes[:, b, 0, 0]) & (s <= chunk_boxes[:, b, 1, 0])
            mask &= (r2 >= r_min * r_min) & (r2 <= r_max2)
            if obstacle is not None:
                mask &= obstacle
            flat = np.flatnonzero(mask)
            if flat.size == 0:
                continue
            r = np.sqrt(r2.flat[flat])
            theta = np.arctan2(v.flat[flat], u.flat[flat])
            _mark_arcs(r, theta, flat % n, boxes[0, b], n_roll, diff)
        # Points covering each roll (a point's arcs in one box are disjoint, the boxes too).
        inside = np.cumsum(diff, axis=1)[:, : 4 * n_roll].reshape(n, 4, n_roll).sum(axis=1)
        out[sl] = inside > max_points
    return out


def eliminate(
    cands: CandidateSet,
    points: NDArray,
    gripper: GripperModel,
    config: GraspConfig,
    support_plane: NDArray | None = None,
    seed: int = 0,
    line_priority: NDArray | None = None,
    camera_positions: NDArray | None = None,
) -> EliminationReport:
    """Run the rules on ``cands`` in place (fills ``rejected_by``); returns the counts.

    ``line_priority`` (L,) decides which of duplicate lines stays (higher wins; default: the
    first); the planner passes ``h_alpha h_beta`` of each line's superquadric.
    ``camera_positions`` (C, 3): with them, a contact no camera can see needs no support (rule 2).
    """
    n_roll = cands.n_roll
    L = cands.lines
    # code[line, roll]: 0 while kept, else 1 + the index of the rule that removed it.
    code = np.zeros((len(L), n_roll), dtype=np.int8)
    remaining = {"synthesised": len(cands)}
    points = voxel_downsample(points, config.elimination_voxel_m).points

    def apply(rule: str, lines: NDArray[np.int64], hit: NDArray[np.bool_]) -> None:
        """Mark rolls ``hit`` (len(lines), R) or whole lines (hit (len(lines),)) as removed."""
        block = code[lines]
        mask = hit if hit.ndim == 2 else np.broadcast_to(hit[:, None], block.shape)
        block[(block == 0) & mask] = 1 + REJECTION_REASONS.index(rule)
        code[lines] = block
        remaining[rule] = int(np.count_nonzero(code == 0))

    def alive_lines() -> NDArray[np.int64]:
        return np.flatnonzero(np.any(code == 0, axis=1))

    all_lines = np.arange(len(L))
    priority = np.zeros(len(L)) if line_priority is None else np.asarray(line_priority, float)
    apply("duplicate", all_lines, duplicate_lines(L, priority, config))
    apply(
        "width", all_lines, 2.0 * L.half_lengths > gripper.max_opening_m - config.opening_margin_m
    )

    spacing = cloud_spacing(points, seed)
    kappa = support_kappa(spacing, config)
    lines = alive_lines()
    stats = support_stats(points, cands, lines, config)
    facing = stats.cos_tilt >= np.cos(np.deg2rad(config.support_max_tilt_deg))
    supported = (stats.counts >= kappa) & facing
    if camera_positions is not None:
        unseen = unobservable_contacts(cands, lines, camera_positions, config, support_plane)
        ok = np.all(supported | unseen, axis=1) & np.any(supported, axis=1)
    else:
        ok = np.all(supported, axis=1)
    apply("support", lines, ~ok)

    openings = approach_openings(L.half_lengths, gripper, config)
    L.openings = openings
    lines = alive_lines()
    swept = line_boxes(gripper, openings[lines], config.approach_distance_m)
    if support_plane is not None:
        plane = np.asarray(support_plane, float)
        apply("table", lines, ~table_clear(cands, lines, swept, plane, config.table_clearance_m))
    else:
        remaining["table"] = remaining["support"]

    # The paper's obstacles: between the end planes, outside radius l_j.
    lines = alive_lines()
    half_height = np.minimum(L.half_lengths[lines], 0.5 * gripper.max_opening_m)
    radius = np.full(lines.size, gripper.jaw_length_m)
    body = line_boxes(gripper, openings[lines])
    tolerated = config.max_obstacle_points
    hits = body_hits(points, cands, lines, body, radius, half_height, tolerated)
    apply("collision", lines, hits)

    if config.sweep_rule:
        lines = alive_lines()
        swept = line_boxes(gripper, openings[lines], config.approach_distance_m)
        apply("sweep", lines, body_hits(points, cands, lines, swept, max_points=tolerated))
    else:
        remaining["sweep"] = remaining["collision"]

    names = np.array((KEPT, *REJECTION_REASONS), dtype=cands.rejected_by.dtype)
    cands.rejected_by = names[code.ravel()]
    return EliminationReport(
        remaining=remaining, kappa=kappa, spacing_m=spacing, n_points=points.shape[0]
    )
