"""The oracle: what this hand can grasp at all, from the true object meshes and poses.

**Privileged on purpose.** The oracle reads the simulator's truth (``PlanningContext.truth``:
every object's collision hulls in the world frame), information no other planner gets, and it
never reads the cloud. Its GSR is the ceiling of this hand in this harness, not a method to
compare with; tables mark its row as privileged. A presentation on which it finds no feasible
grasp is ``graspable = false`` (:func:`feasible_grasps`, run by the trial runner for every
planner on the same pose).

The search, per object on the table:

1. Sample contact points on the object's surface (the hulls' facets, area-weighted; points
   inside another hull of the same object are not surface and are dropped).
2. Keep antipodal pairs: the line between the two contacts lies within the friction cone of
   both facets (``friction_coefficient``), the contacts are ``min_width_m`` to the opening less
   ``opening_margin_m`` apart, and the segment between them runs inside the object (a pair
   across the gap of a handle is no pinch).
3. Each pair is a closing line with rolls about it every ``roll_step_deg``; the planner's own
   rules remove poses whose open fingers or palm (swept back along the approach) would enter the
   table, then, on lines left with a roll clear of the table, poses that would touch the true
   surface of any object within the hand's reach. The graspability check stops per object at
   the first batch of lines holding a feasible pose.

Survivors are scored by how well the line sits in both cones and how nearly the hand comes
from above (the trial runner tries them in that order).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.config import load_config
from hsqbench.planner.api import PlanningContext, PlanResult
from hsqbench.planner.gripper import GripperModel, resolve_gripper
from hsqbench.planner.hsq.config import GraspConfig, resolve_config
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet, ClosingLines, roll_frames
from hsqbench.planner.hsq.stage_two.elimination import approach_openings, body_hits, line_boxes
from hsqbench.planner.truth import HandTruth, ObjectTruth, SceneTruth

#: A facet point this close to another hull of the same object is on a joint between hulls (CoACD
#: hulls touch along their cut planes), metres.
JOIN_TOLERANCE_M = 1e-3


@dataclass(frozen=True)
class OracleConfig:
    """``configs/oracle.yaml`` (reasons there). Lengths in metres, angles in degrees."""

    contact_samples: int = 500
    obstacle_spacing_m: float = 0.006
    friction_coefficient: float | None = None
    min_width_m: float = 0.005
    table_clearance_m: float = 0.002
    contact_shifts: int = 4
    pad_edge_margin_m: float = 0.002
    max_pairs_per_object: int = 3000
    max_lines_per_object: int = 150
    batch_lines: int = 25
    roll_step_deg: float = 15.0
    inside_checks: int = 5
    inside_margin_m: float = 0.0005
    planner_config: str = "planner"

    def __post_init__(self) -> None:
        if self.contact_samples < 2 or self.max_lines_per_object < 1 or self.inside_checks < 1:
            raise ValueError(
                "oracle: contact_samples >= 2, max_lines_per_object and inside_checks >= 1"
            )
        if not 0 < self.roll_step_deg <= 180 or self.obstacle_spacing_m <= 0:
            raise ValueError("oracle: roll_step_deg in (0, 180], obstacle_spacing_m > 0")
        if self.friction_coefficient is not None and self.friction_coefficient <= 0:
            raise ValueError("oracle: friction_coefficient must be positive or null")
        if self.contact_shifts < 1 or self.table_clearance_m < 0 or self.pad_edge_margin_m < 0:
            raise ValueError(
                "oracle: contact_shifts >= 1, table_clearance_m and pad_edge_margin_m >= 0"
            )


def load_oracle_config(path: str | Path | None = "oracle") -> OracleConfig:
    return load_config(OracleConfig, path)


def sample_surface(
    obj: ObjectTruth, n: int, rng: np.random.Generator
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """About ``n`` points (M, 3) on the object's outer surface with outward normals (M, 3)."""
    tris, normals, owner = [], [], []
    for k, (t, eq) in enumerate(obj.facets):
        tris.append(t)
        normals.append(eq[:, :3])
        owner.append(np.full(len(t), k))
    tri, nrm, own = np.concatenate(tris), np.concatenate(normals), np.concatenate(owner)
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    pick = rng.choice(len(tri), size=n, p=area / area.sum())
    u, v = rng.random((2, n))
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    t = tri[pick]
    pts = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
    # A facet point inside or on another hull of the object lies where hulls overlap or meet (a
    # decomposition's cut planes), inside the object, not on its surface.
    outer = np.ones(n, dtype=bool)
    for k, (_, eq) in enumerate(obj.facets):
        other = own[pick] != k
        outer &= ~(other & np.all(pts @ eq[:, :3].T + eq[:, 3] < JOIN_TOLERANCE_M, axis=1))
    return pts[outer], nrm[pick][outer]


def antipodal_lines(
    obj: ObjectTruth,
    max_width_m: float,
    friction: float,
    config: OracleConfig,
    rng: np.random.Generator,
) -> tuple[ClosingLines, NDArray[np.float64]]:
    """Closing lines between antipodal contact pairs of one object within the friction cone of
    ``friction`` (at most ``max_pairs_per_object``), and each line's cone quality (the smaller cosine between the line
    and the two inward normals)."""
    pts, nrm = sample_surface(obj, config.contact_samples, rng)
    v = pts[None, :, :] - pts[:, None, :]  # (i, j): from contact i to contact j
    w = np.linalg.norm(v, axis=2)
    d = v / np.maximum(w, 1e-12)[..., None]
    cos_cone = np.cos(np.arctan(friction))
    at_i = -np.einsum("ik,ijk->ij", nrm, d)  # the closing direction against i's inward normal
    at_j = np.einsum("jk,ijk->ij", nrm, d)  # ... and along j's outward normal
    ok = (at_i >= cos_cone) & (at_j >= cos_cone) & (w >= config.min_width_m) & (w <= max_width_m)
    ok &= np.triu(np.ones_like(ok), k=1)  # each unordered pair once
    i, j = np.nonzero(ok)
    if i.size > config.max_pairs_per_object:  # bound the cost of the tests below
        keep = np.sort(rng.choice(i.size, config.max_pairs_per_object, replace=False))
        i, j = i[keep], j[keep]
    t = (np.arange(config.inside_checks) + 1.0) / (config.inside_checks + 1.0)
    along = pts[i, None, :] + t[None, :, None] * v[i, j][:, None, :]
    solid = obj.inside(along.reshape(-1, 3), config.inside_margin_m)
    good = np.all(solid.reshape(i.size, config.inside_checks), axis=1)
    i, j = i[good], j[good]
    quality = np.minimum(at_i[i, j], at_j[i, j])
    dirs = d[i, j]
    # Roll 0 approaches as nearly straight down as the line allows (rolls cover the rest).
    down = np.array([0.0, 0.0, -1.0])
    e1 = down - (dirs @ down)[:, None] * dirs
    fallback = np.linalg.norm(e1, axis=1) < 1e-6  # a vertical line: any horizontal approach
    e1[fallback] = np.array([1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    lines = ClosingLines(
        centres=0.5 * (pts[i] + pts[j]),
        directions=dirs,
        approach0=e1,
        half_lengths=0.5 * w[i, j],
        source=np.zeros(i.size, dtype=np.int64),
        axis=np.full(i.size, -1, dtype=np.int64),
        family=np.full(i.size, "antipodal", dtype="<U12"),
    )
    return lines, quality


def _surface_points(obj: ObjectTruth, config: OracleConfig, rng: np.random.Generator) -> NDArray:
    """The object's surface at about ``obstacle_spacing_m``: what the hand must not touch."""
    area = sum(
        0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
        for t, _ in obj.facets
    )
    n = max(config.contact_samples, int(area / config.obstacle_spacing_m**2))
    return sample_surface(obj, n, rng)[0]


def _table_ok(
    lines: ClosingLines,
    rolls: NDArray,
    hand: HandTruth,
    plane: NDArray,
    shifts: NDArray,
    approach_m: float,
    clearance_m: float,
) -> NDArray[np.bool_]:
    """(L, R, S): whether the hand's true collision hulls stay ``clearance_m`` above the table
    at each line, roll and shift, at the grasp and at the pre-grasp ``approach_m`` back along
    the approach (between the two the distance is linear, so those two bound the motion).

    A shift ``s`` moves the hand back along its approach by ``s``: the contacts then sit ``s``
    toward the fingertips on the pads, which lets the hand grasp low on a flat object."""
    frames = roll_frames(lines.directions, lines.approach0, rolls)  # (L, R, 3, 3)
    u = np.einsum("j,lrjk->lrk", plane[:3], frames)  # the table normal in each grasp frame
    half = 0.5 * lines.openings[:, None]
    low = np.minimum.reduce(
        [
            (u @ hand.left_finger.T).min(axis=2) + u[..., 0] * half,
            (u @ hand.right_finger.T).min(axis=2) - u[..., 0] * half,
            (u @ hand.palm.T).min(axis=2),
        ]
    )
    base = lines.centres @ plane[:3] + plane[3]
    dist = base[:, None] + low + np.minimum(0.0, -approach_m * u[..., 2])
    return dist[..., None] - shifts * u[..., 2, None] >= clearance_m


def _poses(
    lines: ClosingLines, rolls: NDArray, feasible: NDArray[np.bool_], shifts: NDArray
) -> tuple[ClosingLines, NDArray[np.bool_]]:
    """Every (line, roll) as a line with a single roll (zero), its centre the TCP: the contacts'
    midpoint moved back along the approach by the first feasible shift (none: no shift).
    Returns those lines, (L * R,), and whether each pose is feasible."""
    frames = roll_frames(lines.directions, lines.approach0, rolls)
    approach = frames[..., 2].reshape(-1, 3)
    ok = feasible.any(axis=2).ravel()
    shift = shifts[np.argmax(feasible, axis=2)].ravel() * ok
    rep = np.repeat(np.arange(len(lines)), rolls.size)
    out = ClosingLines(
        centres=lines.centres[rep] - shift[:, None] * approach,
        directions=lines.directions[rep],
        approach0=approach,
        half_lengths=lines.half_lengths[rep],
        source=lines.source[rep],
        axis=lines.axis[rep],
        family=lines.family[rep],
        openings=lines.openings[rep],
    )
    return out, ok


def _subset(lines: ClosingLines, keep: NDArray[np.int64]) -> ClosingLines:
    return ClosingLines(
        lines.centres[keep],
        lines.directions[keep],
        lines.approach0[keep],
        lines.half_lengths[keep],
        lines.source[keep],
        lines.axis[keep],
        lines.family[keep],
        lines.openings[keep],
    )


def _object_search(
    lines: ClosingLines,
    rolls: NDArray,
    obstacles: NDArray,
    hand: HandTruth,
    gripper: GripperModel,
    grasp_cfg: GraspConfig,
    plane: NDArray,
    shifts: NDArray,
    config: OracleConfig,
    rng: np.random.Generator,
    first_only: bool,
) -> tuple[ClosingLines, NDArray[np.bool_], NDArray[np.int64]]:
    """One object's lines that clear the table at some roll and shift (at most
    ``max_lines_per_object``, drawn at random), and which of their (roll, shift) poses also
    touch nothing; with ``first_only`` the search stops at the first batch holding a feasible
    pose. Returns the lines, (L, R, S) feasibility and the kept lines' indices in ``lines``."""
    lines.openings = approach_openings(lines.half_lengths, gripper, grasp_cfg)
    clear = _table_ok(
        lines, rolls, hand, plane, shifts, grasp_cfg.approach_distance_m, config.table_clearance_m
    )
    alive = rng.permutation(np.flatnonzero(clear.any(axis=(1, 2))))
    alive = alive[: config.max_lines_per_object]
    cands = CandidateSet(lines, rolls)
    swept = line_boxes(gripper, lines.openings, grasp_cfg.approach_distance_m)
    ok = np.zeros((alive.size, rolls.size, shifts.size), dtype=bool)
    for start in range(0, alive.size, config.batch_lines):
        rows = np.arange(start, min(start + config.batch_lines, alive.size))
        sel = alive[rows]
        for k, s in enumerate(shifts):
            if not clear[sel, :, k].any():
                continue
            boxes = swept[sel].copy()
            boxes[..., 2] -= s  # the hand moved back by s along its approach
            ok[rows, :, k] = clear[sel, :, k] & ~body_hits(obstacles, cands, sel, boxes)
        if first_only and ok[rows].any():
            done = rows[-1] + 1
            return _subset(lines, alive[:done]), ok[:done], alive[:done]
    return _subset(lines, alive), ok, alive


def oracle_candidates(
    truth: SceneTruth,
    gripper: GripperModel,
    config: OracleConfig,
    seed: int,
    first_only: bool = False,
) -> tuple[CandidateSet, NDArray[np.int64]]:
    """The scene's feasible-or-not poses (one roll per line: :func:`_poses`) with
    ``rejected_by`` and ``scores`` filled, and the index of the object (in ``truth.objects``)
    each grasps. ``first_only``: per object, stop once a feasible pose is found (enough to tell
    whether it is graspable)."""
    grasp_cfg = resolve_config(config.planner_config).grasp
    hand = truth.hand if truth.hand is not None else _default_hand()
    rng = np.random.default_rng(seed)
    max_width = gripper.max_opening_m - grasp_cfg.opening_margin_m
    rolls = np.deg2rad(np.arange(0.0, 360.0, config.roll_step_deg))
    shifts = np.linspace(0.0, hand.pad_z_m[1] - config.pad_edge_margin_m, config.contact_shifts)
    plane = np.asarray(truth.support_plane, float)
    surfaces = [_surface_points(o, config, rng) for o in truth.objects]
    lows = np.array([s.min(axis=0) for s in surfaces]).reshape(-1, 3)
    highs = np.array([s.max(axis=0) for s in surfaces]).reshape(-1, 3)
    reach = float(np.abs(gripper.boxes(palm_extension_m=grasp_cfg.approach_distance_m)).max())
    reach *= np.sqrt(3.0)  # the farthest box corner from the TCP, at most
    parts, feasible, quality, owner = [], [], [], []
    for k, obj in enumerate(truth.objects):
        mu = config.friction_coefficient or hand.contact_friction(obj)
        lines, q = antipodal_lines(obj, max_width, mu, config, rng)
        # Only objects within the hand's reach of this one can be in its way.
        near = np.all((lows <= highs[k] + reach) & (highs >= lows[k] - reach), axis=1)
        obstacles = np.concatenate([surfaces[m] for m in np.flatnonzero(near)])
        kept, ok, index = _object_search(
            lines, rolls, obstacles, hand, gripper, grasp_cfg, plane, shifts, config, rng,
            first_only,
        )  # fmt: skip
        poses, pose_ok = _poses(kept, rolls, ok, shifts)
        parts.append(poses)
        feasible.append(pose_ok)
        quality.append(np.repeat(q[index], rolls.size))
        owner.append(np.full(len(poses), k))
    lines = ClosingLines.concatenate(parts)
    cands = CandidateSet(lines, np.zeros(1))
    removed = ~np.concatenate(feasible) if parts else np.zeros(0, dtype=bool)
    cands.rejected_by[removed] = "collision"
    q = np.concatenate(quality) if quality else np.zeros(0)
    downness = np.maximum(0.0, -cands.rotations[:, 2, 2]) if len(cands) else np.zeros(0)
    cands.scores = np.where(removed, np.nan, q * (0.5 + 0.5 * downness))
    owners = np.concatenate(owner) if owner else np.zeros(0, dtype=np.int64)
    return cands, owners


def _default_hand() -> HandTruth:
    """The Panda's hand for a scene made outside the simulator (``SceneTruth.hand`` None)."""
    from hsqbench.sim.scene_truth import panda_hand

    return panda_hand()


def feasible_grasps(
    truth: SceneTruth, gripper: GripperModel, config: OracleConfig, seed: int
) -> dict[str, int]:
    """Per object name, feasible oracle grasps found (0: not graspable here); the search stops
    at the first feasible batch of lines per object, so a positive count is a lower bound."""
    cands, owner = oracle_candidates(truth, gripper, config, seed, first_only=True)
    counts = np.bincount(owner[cands.kept], minlength=len(truth.objects))
    return {o.name: int(c) for o, c in zip(truth.objects, counts, strict=True)}


class OraclePlanner:
    """Privileged planner: grasps from the true meshes (module docstring). Never reads the cloud."""

    name = "oracle"
    #: The trial runner gives ``context.truth`` only to planners that say this.
    privileged = True

    def __init__(self, config: OracleConfig | str | Path | None = None) -> None:
        self.config = (
            config if isinstance(config, OracleConfig) else load_oracle_config(config or "oracle")
        )
        self.gripper = resolve_gripper(resolve_config(self.config.planner_config).grasp.gripper)

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult:
        del points  # privileged: the truth replaces perception entirely
        if context.truth is None:
            raise ValueError(
                "the oracle needs the scene's truth (PlanningContext.truth); the trial runner "
                "gives it to privileged planners only"
            )
        t0 = time.perf_counter()
        # The presentation's seed, not the context's: the graspability check searched the same
        # samples, so the oracle finds a grasp exactly where it marked the presentation graspable.
        cands, _ = oracle_candidates(context.truth, self.gripper, self.config, context.truth.seed)
        grasps = cands.ranked()
        total = time.perf_counter() - t0
        return PlanResult(
            grasps=grasps,
            candidates=cands,
            remaining={"synthesised": len(cands), "collision": int(cands.kept.sum())},
            timings={"total": total},
            reason="" if len(grasps) else "no antipodal pair of the true surfaces is feasible",
            planner=self.name,
        )
