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
   rules, on the true surfaces of every object in the scene, remove poses whose open fingers or
   palm (swept back along the approach) would enter the table or touch any object.

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
from hsqbench.planner.api import PlanningContext, PlanResult, resolve_config, resolve_gripper
from hsqbench.planner.candidates import CandidateSet, ClosingLines
from hsqbench.planner.elimination import approach_openings, body_hits, line_boxes, table_clear
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.truth import ObjectTruth, SceneTruth

#: A facet point this close to another hull of the same object is on a joint between hulls (CoACD
#: hulls touch along their cut planes), metres.
JOIN_TOLERANCE_M = 1e-3


@dataclass(frozen=True)
class OracleConfig:
    """``configs/oracle.yaml`` (reasons there). Lengths in metres, angles in degrees."""

    contact_samples: int = 300
    obstacle_spacing_m: float = 0.005
    friction_coefficient: float = 0.5
    min_width_m: float = 0.005
    max_lines_per_object: int = 60
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
        if self.friction_coefficient <= 0:
            raise ValueError("oracle: friction_coefficient must be positive")


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
    config: OracleConfig,
    rng: np.random.Generator,
) -> tuple[ClosingLines, NDArray[np.float64]]:
    """Closing lines between antipodal contact pairs of one object, and each line's cone quality
    (the smaller cosine between the line and the two inward normals)."""
    pts, nrm = sample_surface(obj, config.contact_samples, rng)
    v = pts[None, :, :] - pts[:, None, :]  # (i, j): from contact i to contact j
    w = np.linalg.norm(v, axis=2)
    d = v / np.maximum(w, 1e-12)[..., None]
    cos_cone = np.cos(np.arctan(config.friction_coefficient))
    at_i = -np.einsum("ik,ijk->ij", nrm, d)  # the closing direction against i's inward normal
    at_j = np.einsum("jk,ijk->ij", nrm, d)  # ... and along j's outward normal
    ok = (at_i >= cos_cone) & (at_j >= cos_cone) & (w >= config.min_width_m) & (w <= max_width_m)
    ok &= np.triu(np.ones_like(ok), k=1)  # each unordered pair once
    i, j = np.nonzero(ok)
    if i.size > 4 * config.max_lines_per_object:  # bound the inside check's cost
        keep = rng.choice(i.size, 4 * config.max_lines_per_object, replace=False)
        i, j = i[np.sort(keep)], j[np.sort(keep)]
    t = (np.arange(config.inside_checks) + 1.0) / (config.inside_checks + 1.0)
    along = pts[i, None, :] + t[None, :, None] * v[i, j][:, None, :]
    solid = obj.inside(along.reshape(-1, 3), config.inside_margin_m)
    solid = solid.reshape(i.size, config.inside_checks)
    good = np.all(solid, axis=1)
    i, j = i[good], j[good]
    if i.size > config.max_lines_per_object:
        keep = np.sort(rng.choice(i.size, config.max_lines_per_object, replace=False))
        i, j = i[keep], j[keep]
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


def obstacle_points(truth: SceneTruth, config: OracleConfig, rng: np.random.Generator) -> NDArray:
    """Every object's surface at about ``obstacle_spacing_m``: what the hand must not touch."""
    out = []
    for obj in truth.objects:
        area = sum(
            0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum()
            for t, _ in obj.facets
        )
        n = max(config.contact_samples, int(area / config.obstacle_spacing_m**2))
        out.append(sample_surface(obj, n, rng)[0])
    return np.concatenate(out) if out else np.zeros((0, 3))


def oracle_candidates(
    truth: SceneTruth,
    gripper: GripperModel,
    config: OracleConfig,
    seed: int,
) -> tuple[CandidateSet, NDArray[np.int64]]:
    """All antipodal candidates of the scene with ``rejected_by`` and ``scores`` filled, and the
    index of the object (in ``truth.objects``) each candidate grasps."""
    grasp_cfg = resolve_config(config.planner_config).grasp
    rng = np.random.default_rng(seed)
    max_width = gripper.max_opening_m - grasp_cfg.opening_margin_m
    parts, quality, owner = [], [], []
    for k, obj in enumerate(truth.objects):
        lines, q = antipodal_lines(obj, max_width, config, rng)
        parts.append(lines)
        quality.append(q)
        owner.append(np.full(len(lines), k))
    lines = ClosingLines.concatenate(parts)
    rolls = np.deg2rad(np.arange(0.0, 360.0, config.roll_step_deg))
    cands = CandidateSet(lines, rolls)
    code = np.zeros((len(lines), rolls.size), dtype=bool)  # True: removed
    if len(lines):
        lines.openings = approach_openings(lines.half_lengths, gripper, grasp_cfg)
        idx = np.arange(len(lines))
        swept = line_boxes(gripper, lines.openings, grasp_cfg.approach_distance_m)
        plane = np.asarray(truth.support_plane, float)
        code |= ~table_clear(cands, idx, swept, plane, grasp_cfg.table_clearance_m)
        alive = np.flatnonzero(~np.all(code, axis=1))
        points = obstacle_points(truth, config, rng)
        code[alive] |= body_hits(points, cands, alive, swept[alive])
    removed = code.ravel()
    cands.rejected_by[removed] = "collision"
    q = np.repeat(np.concatenate(quality) if quality else np.zeros(0), rolls.size)
    downness = np.maximum(0.0, -cands.rotations[:, 2, 2]) if len(cands) else np.zeros(0)
    cands.scores = np.where(removed, np.nan, q * (0.5 + 0.5 * downness))
    return cands, np.repeat(np.concatenate(owner) if owner else np.zeros(0, int), rolls.size)


def feasible_grasps(
    truth: SceneTruth, gripper: GripperModel, config: OracleConfig, seed: int
) -> dict[str, int]:
    """Feasible oracle grasps per object name (0: that object is not graspable here)."""
    cands, owner = oracle_candidates(truth, gripper, config, seed)
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
        seed = 0 if context.seed is None else int(context.seed)
        cands, _ = oracle_candidates(context.truth, self.gripper, self.config, seed)
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
