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
   Where rule 6 runs (hidden bodies, which need the cameras) the facing test does not: besides
   edges, it was what kept fingers out of bodies no camera saw (no points there, so the collision
   rules cannot), and it also removed real contacts on thin walls, bags and tools lying flat,
   whose support cylinders hold more of the top surface than of the side. Rule 6 models those
   bodies instead.
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
5. ``sweep`` (addition, ``sweep_rule``): the paper only looks between the end planes. Any cloud
   point in the volume the hand sweeps also removes the pose: the open fingers, and the palm
   swept back by ``approach_distance_m`` (the straight-line approach from the pre-grasp pose).
   E.g. a body no camera sees, beside a finger that grips a thin part in front of it.
6. ``hidden`` (addition, ``body_rule``): the same test against obstacle points that model what
   no camera saw: the surfaces of the hidden superquadrics, shrunk by ``body_margin_m``, less
   the samples a camera saw through (:mod:`~hsqbench.planner.hsq.stage_two.hidden_bodies`). E.g. a body
   behind a handle that hides it from the cameras, where the cloud holds no point. Only
   planners with superquadrics pass such points (``body_points``); for the others the rule
   removes nothing.

Rules 4 to 6 are exact for the box model of the gripper and cost O(lines x points), not
O(candidates x points): in the frame of a line (``s`` along it, polar ``r, theta`` about it) a
point is inside a box at roll ``phi`` iff ``s`` is within the box's extent along the closing axis
and ``psi = theta - phi`` satisfies ``r cos(psi) in [z_lo, z_hi]`` and ``|r sin(psi)| <= y_half``:
at most four arcs of ``phi``, which mark the discrete rolls they contain.

The rules' geometry lives in :mod:`~hsqbench.planner.hsq.stage_two.support` (rule 2),
:mod:`~hsqbench.planner.hsq.stage_two.roll_collisions` (rules 4 and 5) and :mod:`~hsqbench.planner.hsq.stage_two.line_frame`;
their public names stay importable from here.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import (
    KEPT,
    REJECTION_REASONS,
    CandidateSet,
    ClosingLines,
    roll_frames,
)
from hsqbench.planner.hsq.stage_two.roll_collisions import body_hits
from hsqbench.planner.hsq.stage_two.support import (
    SupportStats,
    cloud_spacing,
    support_kappa,
    support_stats,
    unobservable_contacts,
)

__all__ = [
    "RULE_DESCRIPTIONS",
    "EliminationReport",
    "SupportStats",
    "approach_openings",
    "body_hits",
    "cloud_spacing",
    "duplicate_lines",
    "eliminate",
    "line_boxes",
    "support_kappa",
    "support_stats",
    "table_clear",
    "unobservable_contacts",
]

#: One line per rule, for messages and the viewer's legend.
RULE_DESCRIPTIONS = {
    "duplicate": "the same closing line from a better-fitting hidden superquadric",
    "width": "contacts farther apart than the gripper opens",
    "support": "too few cloud points at a contact, or no surface there facing the finger",
    "table": "fingers or palm would enter the support plane",
    "collision": "paper's test: object points outside the jaw's reach between the fingers",
    "sweep": "a cloud point in the open fingers or in the palm's approach path",
    "hidden": "the open fingers or the palm's approach path enter a hidden superquadric where "
    "no camera saw free space",
}


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


def _supported(
    points: NDArray,
    cands: CandidateSet,
    lines: NDArray[np.int64],
    config: GraspConfig,
    kappa: int,
    camera_positions: NDArray | None,
    support_plane: NDArray | None,
    facing: bool = True,
) -> NDArray[np.bool_]:
    """(len(lines),): lines that pass rule 2 (both contacts supported, or one supported and the
    other unseen by every camera); ``facing``: with the facing test."""
    stats = support_stats(points, cands, lines, config)
    supported = stats.counts >= kappa
    if facing:
        supported &= stats.cos_tilt >= np.cos(np.deg2rad(config.support_max_tilt_deg))
    if camera_positions is not None:
        unseen = unobservable_contacts(cands, lines, camera_positions, config, support_plane)
        ok = np.all(supported | unseen, axis=1) & np.any(supported, axis=1)
    else:
        ok = np.all(supported, axis=1)
    return ok


def _collision_hits(
    points: NDArray,
    cands: CandidateSet,
    lines: NDArray[np.int64],
    gripper: GripperModel,
    openings: NDArray,
    tolerated: int,
) -> NDArray[np.bool_]:
    """(len(lines), R): rule 4, the paper's obstacles (between the end planes, outside ``l_j``)
    inside the open gripper body."""
    L = cands.lines
    half_height = np.minimum(L.half_lengths[lines], 0.5 * gripper.max_opening_m)
    radius = np.full(lines.size, gripper.jaw_length_m)
    body = line_boxes(gripper, openings[lines])
    return body_hits(points, cands, lines, body, radius, half_height, tolerated)


class _Fates:
    """The fate of every (line, roll) while the rules run: ``code[line, roll]`` is 0 while kept,
    else 1 + the index in ``REJECTION_REASONS`` of the first rule that removed it; ``remaining``:
    the candidates left after each rule, in the order the rules ran."""

    def __init__(self, cands: CandidateSet) -> None:
        self.code = np.zeros((len(cands.lines), cands.n_roll), dtype=np.int8)
        self.remaining = {"synthesised": len(cands)}

    def apply(self, rule: str, lines: NDArray[np.int64], hit: NDArray[np.bool_]) -> None:
        """Mark rolls ``hit`` (len(lines), R) or whole lines (hit (len(lines),)) as removed."""
        block = self.code[lines]
        mask = hit if hit.ndim == 2 else np.broadcast_to(hit[:, None], block.shape)
        block[(block == 0) & mask] = 1 + REJECTION_REASONS.index(rule)
        self.code[lines] = block
        self.skip(rule)

    def skip(self, rule: str) -> None:
        """Record a rule that did not run (it removed nothing)."""
        self.remaining[rule] = int(np.count_nonzero(self.code == 0))

    def alive_lines(self) -> NDArray[np.int64]:
        """Lines with at least one roll still kept."""
        return np.flatnonzero(np.any(self.code == 0, axis=1))

    def rejected_by(self, dtype: np.dtype) -> NDArray:
        """(N,): each candidate's fate, ``KEPT`` or the rule that removed it."""
        names = np.array((KEPT, *REJECTION_REASONS), dtype=dtype)
        return names[self.code.ravel()]


def _line_rules(
    fates: _Fates,
    lines: ClosingLines,
    gripper: GripperModel,
    config: GraspConfig,
    line_priority: NDArray | None,
) -> None:
    """Rules 0 and 1, on whole lines: ``duplicate`` and ``width``."""
    all_lines = np.arange(len(lines))
    priority = np.zeros(len(lines)) if line_priority is None else np.asarray(line_priority, float)
    fates.apply("duplicate", all_lines, duplicate_lines(lines, priority, config))
    too_wide = 2.0 * lines.half_lengths > gripper.max_opening_m - config.opening_margin_m
    fates.apply("width", all_lines, too_wide)


def _obstacle_rules(
    fates: _Fates,
    points: NDArray,
    cands: CandidateSet,
    gripper: GripperModel,
    config: GraspConfig,
    body_points: NDArray | Callable[[], NDArray] | None,
) -> None:
    """Rules 4 to 6 (``collision``, ``sweep``, ``hidden``) on the lines still alive; rule 6 runs
    only with ``body_points`` (None: it removes nothing)."""
    openings = cands.lines.openings
    tolerated = config.max_obstacle_points
    # The paper's obstacles: between the end planes, outside radius l_j.
    lines = fates.alive_lines()
    fates.apply(
        "collision", lines, _collision_hits(points, cands, lines, gripper, openings, tolerated)
    )
    if config.sweep_rule:
        lines = fates.alive_lines()
        swept = line_boxes(gripper, openings[lines], config.approach_distance_m)
        fates.apply("sweep", lines, body_hits(points, cands, lines, swept, max_points=tolerated))
    else:
        fates.skip("sweep")
    lines = fates.alive_lines()
    if body_points is not None and lines.size:
        obstacles = body_points() if callable(body_points) else body_points
        swept = line_boxes(gripper, openings[lines], config.approach_distance_m)
        fates.apply(
            "hidden", lines, body_hits(obstacles, cands, lines, swept, max_points=tolerated)
        )
    else:
        fates.skip("hidden")


def eliminate(
    cands: CandidateSet,
    points: NDArray,
    gripper: GripperModel,
    config: GraspConfig,
    support_plane: NDArray | None = None,
    seed: int = 0,
    line_priority: NDArray | None = None,
    camera_positions: NDArray | None = None,
    body_points: NDArray | Callable[[], NDArray] | None = None,
) -> EliminationReport:
    """Run the rules on ``cands`` in place (fills ``rejected_by``); returns the counts.

    ``line_priority`` (L,) decides which of duplicate lines stays (higher wins; default: the
    first); the planner passes ``h_alpha h_beta`` of each line's superquadric.
    ``camera_positions`` (C, 3): with them, a contact no camera can see needs no support (rule 2).
    ``body_points`` (M, 3): rule 6's obstacles (:func:`~hsqbench.planner.hsq.stage_two.hidden_bodies.
    body_obstacles`), or a function returning them, called only if a candidate reaches rule 6;
    None: the rule removes nothing.
    """
    L = cands.lines
    fates = _Fates(cands)
    points = voxel_downsample(points, config.elimination_voxel_m).points
    _line_rules(fates, L, gripper, config, line_priority)

    spacing = cloud_spacing(points, seed)
    kappa = support_kappa(spacing, config)
    lines = fates.alive_lines()
    # Rule 6 replaces the facing test where it runs (see the module docstring).
    bodies = config.body_rule and body_points is not None
    ok = _supported(
        points, cands, lines, config, kappa, camera_positions, support_plane, facing=not bodies
    )
    fates.apply("support", lines, ~ok)

    L.openings = approach_openings(L.half_lengths, gripper, config)
    lines = fates.alive_lines()
    if support_plane is not None:
        swept = line_boxes(gripper, L.openings[lines], config.approach_distance_m)
        plane = np.asarray(support_plane, float)
        fates.apply(
            "table", lines, ~table_clear(cands, lines, swept, plane, config.table_clearance_m)
        )
    else:
        fates.skip("table")

    _obstacle_rules(fates, points, cands, gripper, config, body_points if bodies else None)
    cands.rejected_by = fates.rejected_by(cands.rejected_by.dtype)
    return EliminationReport(
        remaining=fates.remaining, kappa=kappa, spacing_m=spacing, n_points=points.shape[0]
    )
