"""The ``antipodal`` baseline: learning-free antipodal point pairs, as GPD / Dex-Net sample them.

Sampling (after Dex-Net's antipodal grasp sampler and GPD's candidate generation, written from
their published descriptions):

1. Voxel-downsample the cloud (``voxel_m``), estimate PCA normals over ``k`` neighbours and
   orient them outward (:mod:`.normals`).
2. Draw ``n_samples`` points ``p`` without replacement (``np.random.default_rng(seed)``).
3. Cast a ray from each ``p`` along its inward normal ``-n_p``; its first hit ``q`` is the cloud
   point within ``ray_radius_m`` of the ray with the smallest distance ``t > min_width_m`` along
   it (nearer points are ``p``'s own surface).
4. The closing axis is ``d = (q - p) / |q - p|``. The pair is antipodal when ``d`` lies in both
   friction cones of half angle ``theta_f``: ``angle(-n_p, d) <= theta_f`` and
   ``angle(n_q, d) <= theta_f`` (Nguyen's condition for a two-finger force closure).
5. Each pair gives a closing line (``P_G`` the midpoint, half length ``|q - p| / 2``), and the
   gripper is rolled about it every ``roll_step_deg``; roll 0 approaches from above (along
   minus the support plane's normal, or world ``-z`` without a plane).

Input and elimination are the hsq planner's own: isolated points are removed first
(``cleaning:`` of the planner config, :func:`hsqbench.planner.cleaning.clean_cloud`), and
:func:`hsqbench.planner.hsq.stage_two.elimination.eliminate` runs on the same
:class:`~hsqbench.planner.hsq.stage_two.candidates.CandidateSet`: all of its rules (width, support, table,
collision, sweep, and any added later) with the same gripper, settings and camera positions (a
contact no camera sees needs no support), so the planners differ only in where the closing
lines come from and how they are scored.

Score (documented heuristic, in (0, 1]): ``h = h_antipodal * h_delta``,

- ``h_antipodal = exp(-(theta_p^2 + theta_q^2) / (2 theta_f^2))``: 1 for normals exactly along
  the axis, ``e^-1`` with both normals on the cone's boundary;
- ``h_delta = exp(-delta^2 / q_delta)``, ``delta`` the distance from ``P_G`` to the cloud's
  centroid in metres, with the hsq planner's ``q_delta`` (GPD-style preference for grasps near
  the object's centre); left out in packed scenes, as for hsq.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import (
    PlanningContext,
    PlanResult,
    validate_cameras,
    validate_plane,
)
from hsqbench.planner.base import CleanInput, rules_removed_reason
from hsqbench.planner.baselines.config import (
    AntipodalConfig,
    BaselinesConfig,
)
from hsqbench.planner.baselines.normals import estimate_normals, orient_outward
from hsqbench.planner.baselines.planner import BaselinePlanner
from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import REJECTION_REASONS, CandidateSet, ClosingLines
from hsqbench.planner.hsq.stage_two.elimination import eliminate
from hsqbench.planner.hsq.stage_two.synthesis import roll_angles

Array = NDArray[np.float64]

FAMILY = "antipodal"
FACTOR_NAMES = ("h_antipodal", "h_delta")
#: Raw measures behind the factors: contact angles to the axis (radians), centroid distance (m).
MEASURE_NAMES = ("theta_p", "theta_q", "delta_m")
#: Sample-by-point pairs handled at once when casting rays (memory bound).
_CHUNK_PAIRS = 1_000_000


@dataclass(frozen=True)
class AntipodalPairs:
    """What the ray casting found.

    Attributes:
        p, q: (P, 3) the first and the second contact of each antipodal pair, metres.
        theta_p, theta_q: (P,) angle between the closing axis and the inward normal at ``p`` /
            the outward normal at ``q``, radians (both within the friction cone).
        n_samples: points sampled.
        n_hits: rays that hit the cloud.
    """

    p: Array
    q: Array
    theta_p: Array
    theta_q: Array
    n_samples: int
    n_hits: int

    def __len__(self) -> int:
        return int(self.p.shape[0])


def pair_dots(a: Array, b: Array) -> Array:
    """(n, m) dot products of the rows of ``a`` (n, 3) and ``b`` (m, 3), as broadcast sums:
    ``a @ b.T`` is too skinny for BLAS, whose threads only add overhead on a busy machine."""
    return a[:, 0, None] * b[:, 0] + a[:, 1, None] * b[:, 1] + a[:, 2, None] * b[:, 2]


def cast_rays(points: Array, origins: Array, directions: Array, radius: float, t_min: float):
    """First hit of each ray: the point within ``radius`` of it with the least ``t > t_min``.

    Returns ``(index (S,), found (S,))``; ``index`` is meaningless where ``found`` is False.
    """
    s = origins.shape[0]
    index = np.zeros(s, dtype=np.int64)
    found = np.zeros(s, dtype=bool)
    # |x - o|^2 and (x - o) . d from products with the points, not (S, M, 3) differences;
    # written as broadcast sums: (S, 3) x (3, M) is too skinny for BLAS, whose threads only add
    # overhead on a busy machine.
    sq_norm = np.einsum("ij,ij->i", points, points)
    block = max(1, _CHUNK_PAIRS // max(points.shape[0], 1))
    for start in range(0, s, block):
        o, d = origins[start : start + block], directions[start : start + block]
        t = pair_dots(d, points) - np.einsum("ij,ij->i", o, d)[:, None]
        dist2 = sq_norm[None, :] - 2.0 * pair_dots(o, points) + np.einsum("ij,ij->i", o, o)[:, None]
        t_hit = np.where((t > t_min) & (dist2 - t * t <= radius * radius), t, np.inf)
        j = np.argmin(t_hit, axis=1)
        index[start : start + block] = j
        found[start : start + block] = np.isfinite(t_hit[np.arange(len(o)), j])
    return index, found


def sample_antipodal_pairs(
    points: Array, normals: Array, config: AntipodalConfig, rng: np.random.Generator
) -> AntipodalPairs:
    """Steps 2-4 of the module notes on a (downsampled) cloud with outward unit normals."""
    m = points.shape[0]
    picks = rng.choice(m, size=min(config.n_samples, m), replace=False)
    p, n_p = points[picks], normals[picks]
    hit, found = cast_rays(points, p, -n_p, config.ray_radius_m, config.min_width_m)
    p, n_p, q, n_q = p[found], n_p[found], points[hit[found]], normals[hit[found]]
    axis = q - p
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    theta_p = np.arccos(np.clip(-np.einsum("ij,ij->i", n_p, axis), -1.0, 1.0))
    theta_q = np.arccos(np.clip(np.einsum("ij,ij->i", n_q, axis), -1.0, 1.0))
    cone = np.deg2rad(config.friction_half_angle_deg)
    ok = (theta_p <= cone) & (theta_q <= cone)
    return AntipodalPairs(p[ok], q[ok], theta_p[ok], theta_q[ok], int(picks.size), int(found.sum()))


def closing_lines(pairs: AntipodalPairs, up: Array) -> ClosingLines:
    """One closing line per pair; ``approach0`` is ``-up`` made perpendicular to the line."""
    axis = pairs.q - pairs.p
    length = np.linalg.norm(axis, axis=1)
    d = axis / length[:, None]
    a0 = -up[None, :] - np.einsum("ij,j->i", d, -up)[:, None] * d
    norm = np.linalg.norm(a0, axis=1)
    # A vertical line: any horizontal approach (x, unless the line is along x).
    vertical = norm < 1e-6
    if np.any(vertical):
        helper = np.where(np.abs(d[vertical, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        a0[vertical] = helper - np.einsum("ij,ij->i", helper, d[vertical])[:, None] * d[vertical]
        norm[vertical] = np.linalg.norm(a0[vertical], axis=1)
    n = len(pairs)
    return ClosingLines(
        centres=0.5 * (pairs.p + pairs.q),
        directions=d,
        approach0=a0 / norm[:, None],
        half_lengths=0.5 * length,
        source=np.full(n, -1, dtype=np.int64),
        axis=np.full(n, -1, dtype=np.int64),
        family=np.full(n, FAMILY, dtype="<U12"),
    )


def score_antipodal(
    cands: CandidateSet,
    pairs: AntipodalPairs,
    centroid: Array,
    packed: bool,
    cone_rad: float,
    q_delta: float,
) -> None:
    """Fill ``cands.scores``, ``factors`` and ``measures`` (NaN for eliminated candidates)."""
    n_roll = cands.n_roll
    delta = np.linalg.norm(cands.lines.centres - centroid, axis=1)
    line_factors = {
        "h_antipodal": np.exp(-(pairs.theta_p**2 + pairs.theta_q**2) / (2.0 * cone_rad**2)),
        "h_delta": np.exp(-(delta**2) / q_delta),
    }
    names = FACTOR_NAMES[:1] if packed else FACTOR_NAMES
    score = np.ones(len(pairs))
    for name in names:
        score = score * line_factors[name]
    kept = cands.kept

    def per_candidate(values: Array) -> Array:
        return np.where(kept, np.repeat(values, n_roll), np.nan)

    cands.scores = per_candidate(score)
    cands.factors = {name: per_candidate(line_factors[name]) for name in names}
    cands.measures = {
        "theta_p": per_candidate(pairs.theta_p),
        "theta_q": per_candidate(pairs.theta_q),
        "delta_m": per_candidate(delta),
    }


def _no_grasp_reason(
    pairs: AntipodalPairs,
    cands: CandidateSet,
    remaining: dict[str, int],
    config: AntipodalConfig,
    gripper: GripperModel,
    grasp_config: GraspConfig,
) -> str:
    if len(pairs) == 0:
        return (
            f"none of the {pairs.n_samples} sampled points has an antipodal partner: "
            f"{pairs.n_samples - pairs.n_hits} ray(s) along the inward normal hit no cloud point "
            f"and the {pairs.n_hits} hit(s) are outside the "
            f"{config.friction_half_angle_deg:g} deg friction cones"
        )
    counts = cands.counts_by_reason()
    if remaining["width"] == 0:
        # Lines left before the width rule (rules that run first, if any, drop duplicates).
        steps = list(remaining)
        distinct = remaining[steps[steps.index("width") - 1]] // cands.n_roll
        narrowest = 2.0 * float(np.min(cands.lines.half_lengths))
        return (
            f"all {distinct} distinct antipodal pairs (of {len(pairs)} found) are wider than the "
            f"{gripper.max_opening_m:g} m "
            f"opening (less a {grasp_config.opening_margin_m:g} m margin); the narrowest is "
            f"{narrowest:.3f} m"
        )
    return rules_removed_reason(
        counts,
        f"no candidate survived: of {len(cands)} candidates on {len(pairs)} antipodal pairs, "
        "the rules removed ",
    )


def plan_antipodal(
    points: ArrayLike,
    config: BaselinesConfig | str | Path | None = None,
    *,
    packed: bool = False,
    support_plane: ArrayLike | None = None,
    seed: int | None = None,
    gripper: GripperModel | None = None,
    camera_positions: ArrayLike | None = None,
) -> PlanResult:
    """Antipodal pairs of the cleaned cloud, turned into grasps and ranked (see the module notes).

    Args:
        points: (N, 3) cloud of the object(s), world metres, table removed.
        config: a :class:`BaselinesConfig`, a config name or a YAML path; None: baselines.yaml.
        packed: a packed scene (``h_delta`` left out).
        support_plane: the table ``(a, b, c, d)``, unit normal toward the free side.
        seed: for the sampled points (None = 0: deterministic by default, as hsq).
        gripper: default: the gripper of the planner config's ``grasp:`` section.
        camera_positions: (C, 3) camera centres, metres, if known: contacts no camera can see
            then need no support, as for hsq.

    Raises:
        ValueError: an empty, non-finite or badly shaped cloud, or one with fewer points than
            ``normal_neighbours`` after cleaning and downsampling; a bad plane, camera array
            or config.
    """
    context = PlanningContext(
        support_plane=support_plane, packed=packed, seed=seed, camera_positions=camera_positions
    )
    return AntipodalPlanner(config, gripper).plan(points, context)


class AntipodalPlanner(BaselinePlanner):
    """The antipodal baseline behind the :class:`~hsqbench.planner.api.Planner` protocol."""

    name = "antipodal"

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """Normals, antipodal pairs, the shared elimination rules and the antipodal score."""
        acfg, gcfg, grip = self.config.antipodal, self.planner_config.grasp, self.gripper
        plane = validate_plane(context.support_plane)
        cameras = validate_cameras(context.camera_positions)
        seed = context.seed
        cloud = clean.points
        timings: dict[str, float] = {}

        tick = time.perf_counter()
        down = voxel_downsample(cloud, acfg.voxel_m).points
        if down.shape[0] < acfg.normal_neighbours:
            raise ValueError(
                f"the cloud has {down.shape[0]} points after {acfg.voxel_m:g} m voxels, fewer "
                f"than the {acfg.normal_neighbours} neighbours of a normal; lower "
                "antipodal.voxel_m or antipodal.normal_neighbours"
            )
        normals = estimate_normals(down, acfg.normal_neighbours).normals
        normals = orient_outward(down, normals, acfg.orientation_radius_m, acfg.orientation_voxel_m)
        timings["normals"] = time.perf_counter() - tick

        tick = time.perf_counter()
        rng = np.random.default_rng(0 if seed is None else seed)
        pairs = sample_antipodal_pairs(down, normals, acfg, rng)
        up = np.array([0.0, 0.0, 1.0]) if plane is None else plane[:3]
        grasp_cfg = dataclasses.replace(gcfg, roll_step_deg=acfg.roll_step_deg)
        cands = CandidateSet(closing_lines(pairs, up), roll_angles(grasp_cfg))
        timings["sampling"] = time.perf_counter() - tick

        tick = time.perf_counter()
        report = eliminate(
            cands, cloud, grip, gcfg, plane, 0 if seed is None else seed, camera_positions=cameras
        )
        timings["elimination"] = time.perf_counter() - tick

        tick = time.perf_counter()
        cone = np.deg2rad(acfg.friction_half_angle_deg)
        score_antipodal(cands, pairs, cloud.mean(axis=0), context.packed, cone, gcfg.q_delta)
        grasps = cands.ranked()
        timings["scoring"] = time.perf_counter() - tick

        counts = cands.counts_by_reason()
        reason = (
            "" if grasps else _no_grasp_reason(pairs, cands, report.remaining, acfg, grip, gcfg)
        )
        return PlanResult(
            grasps=grasps,
            candidates=cands,
            remaining=report.remaining,
            removed_by={r: counts[r] for r in REJECTION_REASONS},
            timings=timings,
            reason=reason,
        )
