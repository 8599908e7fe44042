"""The planner interface the harness calls, and the paper's planner behind it.

- :class:`PlanningContext`: what the harness knows besides the cloud (table plane, packed scene,
  seed, cameras, workspace).
- :class:`Planner`: the protocol every planner implements, ``plan(points, context)``; baselines
  and users' planners plug in the same way (see :mod:`hsqbench.planner.registry`).
- :class:`PlanResult`: ranked grasps plus everything needed to explain them.
- :func:`plan_grasps`: the paper's two stages; :func:`plan_from_hidden` runs stage two alone on
  given hidden superquadrics (for tests with known shapes, and for replaying stage one).

Support plane convention: ``(a, b, c, d)`` with ``a x + b y + c z + d = 0`` and ``(a, b, c)`` the
unit normal pointing to the free side (up, for a table).
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.config import resolve_config_path
from hsqbench.planner.additions import AdditionsConfig
from hsqbench.planner.base import CleanInput, PlannerBase, rules_removed_reason
from hsqbench.planner.candidates import REJECTION_REASONS, CandidateSet
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.clusters import object_clusters
from hsqbench.planner.config import GraspConfig, PlannerConfig, load_planner_config
from hsqbench.planner.elimination import eliminate
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.gripper import GripperModel, load_gripper
from hsqbench.planner.hidden_bodies import body_obstacles
from hsqbench.planner.scoring import fit_factors, score_candidates
from hsqbench.planner.synthesis import synthesize
from hsqbench.planner.table_lines import level_table_lines
from hsqbench.superquadric import Superquadric, as_points


def validate_cloud(points: ArrayLike) -> NDArray[np.float64]:
    """The cloud as (N, 3) float64, or a ValueError naming the problem and the fix."""
    try:
        cloud = as_points(points)
    except ValueError as exc:
        raise ValueError(f"the point cloud must be an (N, 3) array of metres: {exc}") from None
    if cloud.shape[0] == 0:
        raise ValueError("the point cloud is empty; the planner needs the points of the object(s)")
    finite = np.isfinite(cloud).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise ValueError(
            f"the point cloud has {bad.size} row(s) with NaN or inf (first at index {bad[0]}); "
            "drop them first, e.g. points[np.isfinite(points).all(axis=1)]"
        )
    return cloud


def validate_cameras(cameras: ArrayLike | None) -> NDArray[np.float64] | None:
    """Camera centres as (C, 3) float64, or a ValueError naming the problem."""
    if cameras is None:
        return None
    arr = np.asarray(cameras, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"camera_positions must be a (C, 3) array of finite metres, got shape {arr.shape}"
        )
    return arr


def validate_plane(plane: ArrayLike | None) -> NDArray[np.float64] | None:
    """``(a, b, c, d)`` scaled so that ``(a, b, c)`` is a unit normal; ValueError if impossible."""
    if plane is None:
        return None
    arr = np.asarray(plane, dtype=np.float64).reshape(-1)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"support_plane must be 4 finite numbers (a, b, c, d), got {plane!r}")
    norm = float(np.linalg.norm(arr[:3]))
    if norm < 1e-9:
        raise ValueError(f"support_plane normal (a, b, c) must not be zero, got {plane!r}")
    return arr / norm


@dataclass(frozen=True)
class PlanningContext:
    """What a planner may use besides the cloud.

    Attributes:
        support_plane: the table ``(a, b, c, d)`` (unit normal toward the free side), or None.
        packed: several objects in the cloud (the paper then drops ``h_delta``).
        seed: for any randomness in the planner; None means the planner's default.
        camera_positions: (C, 3) camera centres, world metres, if known (the hsq planner waives
            the support test at contacts none of them can see).
        workspace_bounds: ``(lower (3,), upper (3,))`` corners of the workspace box, metres, if
            known (ignored by the hsq planner).
        truth: simulator truth (:class:`~hsqbench.planner.truth.SceneTruth`), given only to
            planners that declare ``privileged = True`` (the oracle); None for every other.
    """

    support_plane: tuple[float, float, float, float] | None = None
    packed: bool = False
    seed: int | None = None
    camera_positions: NDArray[np.float64] | None = None
    workspace_bounds: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
    truth: Any = None

    def __post_init__(self) -> None:
        plane = validate_plane(self.support_plane)
        if plane is not None:
            object.__setattr__(self, "support_plane", tuple(float(x) for x in plane))


@runtime_checkable
class Planner(Protocol):
    """Anything that turns a cloud into ranked grasps."""

    name: str

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult: ...


@dataclass
class PlanResult:
    """The outcome of planning on one cloud.

    Attributes:
        grasps: surviving grasps, best first (ties, e.g. the rolls of one closing line, keep
            candidate order); for the hsq planner a lazy :class:`RankedGrasps` sequence.
        hidden_superquadrics: stage one's output (``HiddenSuperquadric`` objects), if any.
        candidates: every candidate with ``rejected_by``, ``scores``, ``factors`` and
            ``measures`` (None for planners without candidates).
        remaining: candidates left after each step, in order: ``synthesised``, then one entry
            per elimination rule (see :data:`~hsqbench.planner.candidates.REJECTION_REASONS`).
        removed_by: how many candidates each rule removed.
        timings: wall-clock seconds per stage (``cleaning``, ``recovery``, ``synthesis``,
            ``elimination``, ``scoring``, ``total``).
        reason: why no grasp survived, in words; ``""`` when there are grasps.
        planner: the planner's name.
        n_removed: input points the planner discarded before planning (the hsq planner's
            cleaning of isolated points, :mod:`hsqbench.planner.cleaning`).
    """

    grasps: Sequence[Grasp]
    hidden_superquadrics: list[Any] = field(default_factory=list)
    candidates: CandidateSet | None = None
    remaining: dict[str, int] = field(default_factory=dict)
    removed_by: dict[str, int] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    reason: str = ""
    planner: str = "hsq"
    n_removed: int = 0

    @property
    def best(self) -> Grasp | None:
        return self.grasps[0] if self.grasps else None

    def to_dict(self, top: int | None = None) -> dict[str, Any]:
        """JSON-ready summary: the ``top`` best grasps (all if None), counts, timings, reason."""
        grasps = self.grasps if top is None else self.grasps[:top]
        return {
            "planner": self.planner,
            "n_grasps": len(self.grasps),
            "grasps": [g.to_dict() for g in grasps],
            "hidden_superquadrics": [_hidden_to_dict(h) for h in self.hidden_superquadrics],
            "remaining": dict(self.remaining),
            "removed_by": dict(self.removed_by),
            "timings": dict(self.timings),
            "reason": self.reason,
            "n_removed": self.n_removed,
        }


def _hidden_to_dict(hidden: Any) -> dict[str, Any]:
    sq = hidden.superquadric
    return {
        "eps1": sq.eps1,
        "eps2": sq.eps2,
        "scale": sq.scale.tolist(),
        "rotation": sq.rotation.tolist(),
        "translation": sq.translation.tolist(),
        "n_inliers": len(hidden.inliers),
        "alpha": float(hidden.alpha),
        "beta": float(hidden.beta),
    }


def resolve_config(config: PlannerConfig | str | Path | None) -> PlannerConfig:
    """A :class:`PlannerConfig` from an instance, a config name or path; None -> planner.yaml.

    Files are parsed once per modification time (planning many clouds re-reads nothing).
    """
    if isinstance(config, PlannerConfig):
        return config
    path = resolve_config_path("planner" if config is None else config)
    return _load_cached(load_planner_config, str(path), path.stat().st_mtime_ns)


def resolve_gripper(name_or_path: str | Path) -> GripperModel:
    """The gripper of ``configs/<name>.yaml`` (or a YAML path), parsed once per modification."""
    path = resolve_config_path(name_or_path)
    return _load_cached(load_gripper, str(path), path.stat().st_mtime_ns)


@functools.lru_cache(maxsize=32)
def _load_cached(loader: Any, path: str, mtime_ns: int) -> Any:
    return loader(path)


def _no_grasp_reason(
    n_hidden: int, cands: CandidateSet, gripper: GripperModel, config: GraspConfig
) -> str:
    if n_hidden == 0:
        return "stage one found no hidden superquadric in the cloud"
    n_lines = len(cands.lines)
    if n_lines == 0:
        return f"the {n_hidden} hidden superquadric(s) gave no closing line"
    counts = cands.counts_by_reason()
    if counts["width"] == len(cands):
        narrowest = 2.0 * float(np.min(cands.lines.half_lengths))
        return (
            f"all {n_lines} closing lines of the {n_hidden} hidden superquadric(s) are wider than "
            f"the {gripper.max_opening_m:g} m opening (less a {config.opening_margin_m:g} m "
            f"margin); the narrowest is {narrowest:.3f} m"
        )
    return rules_removed_reason(
        counts,
        f"no candidate survived: of {len(cands)} candidates on {n_lines} closing lines, the rules "
        "removed ",
    )


def plan_in_context(
    points: ArrayLike,
    hidden: Sequence[Any],
    config: GraspConfig,
    gripper: GripperModel,
    context: PlanningContext,
) -> PlanResult:
    """Stage two (:func:`plan_from_hidden`) with the scene facts of a planning context: the
    stage every superquadric planner (hsq, single-sq) ends with."""
    return plan_from_hidden(
        points,
        hidden,
        config,
        gripper=gripper,
        packed=context.packed,
        support_plane=context.support_plane,
        seed=context.seed,
        camera_positions=context.camera_positions,
    )


def plan_from_hidden(
    points: ArrayLike,
    hidden: Sequence[Any],
    config: GraspConfig | None = None,
    *,
    gripper: GripperModel | None = None,
    packed: bool = False,
    support_plane: ArrayLike | None = None,
    seed: int | None = None,
    camera_positions: ArrayLike | None = None,
) -> PlanResult:
    """Stage two on given hidden superquadrics: synthesis, elimination, scoring, ranking.

    Args:
        points: (N, 3) cloud, metres (the whole cloud: collisions are checked against all of it).
        hidden: objects with ``.superquadric`` (:class:`Superquadric`), ``.alpha`` (metres) and
            ``.beta`` (fraction), e.g. ``HiddenSuperquadric`` from stage one.
        config: stage-two settings; default: ``grasp:`` of ``configs/planner.yaml``.
        gripper: default: ``configs/<config.gripper>.yaml``.
        packed: leave ``h_delta`` out of the score.
        support_plane: the table, ``(a, b, c, d)``; None: no table test. Lines the table
            blocks are levelled and lifted first (:mod:`hsqbench.planner.table_lines`).
        seed: for the subset used to estimate the cloud's spacing (None = 0).
        camera_positions: (C, 3) camera centres, metres; with them, contacts no camera can see
            need no support (``grasp.unseen_incidence_deg``), and rule 6 keeps the hand out of
            the hidden superquadrics where no camera saw free space, in place of the support
            rule's facing test (:mod:`hsqbench.planner.hidden_bodies`). None: every contact
            needs support, and the facing test applies.
    """
    cloud = validate_cloud(points)
    cameras = validate_cameras(camera_positions)
    cfg = config if config is not None else resolve_config(None).grasp
    grip = gripper if gripper is not None else resolve_gripper(cfg.gripper)
    plane = validate_plane(support_plane)
    superquadrics: list[Superquadric] = [h.superquadric for h in hidden]
    timings: dict[str, float] = {}

    start = time.perf_counter()
    cands = synthesize(superquadrics, cfg)
    if plane is not None and cfg.level_table_lines:
        level_table_lines(cands, superquadrics, plane, grip, cfg)
    timings["synthesis"] = time.perf_counter() - start

    start = time.perf_counter()
    alphas = np.array([h.alpha for h in hidden], dtype=np.float64)
    betas = np.array([h.beta for h in hidden], dtype=np.float64)
    h_alpha, h_beta = fit_factors(alphas, betas, cfg)
    priority = (h_alpha * h_beta)[cands.lines.source]
    # Rule 6 needs the cameras: without them an overshooting fit cannot be told from a body.
    # Its obstacles are built only if a candidate reaches it.
    bodies = None
    if cfg.body_rule and cameras is not None:
        bodies = functools.partial(body_obstacles, superquadrics, cloud, cfg, cameras, plane)
    report = eliminate(
        cands, cloud, grip, cfg, plane, 0 if seed is None else seed, priority, cameras, bodies
    )
    timings["elimination"] = time.perf_counter() - start

    start = time.perf_counter()
    score_candidates(cands, superquadrics, alphas, betas, cloud.mean(axis=0), packed, cfg)
    grasps = cands.ranked()
    timings["scoring"] = time.perf_counter() - start

    counts = cands.counts_by_reason()
    return PlanResult(
        grasps=grasps,
        hidden_superquadrics=list(hidden),
        candidates=cands,
        remaining=report.remaining,
        removed_by={r: counts[r] for r in REJECTION_REASONS},
        timings=timings,
        reason="" if grasps else _no_grasp_reason(len(hidden), cands, grip, cfg),
    )


def plan_grasps(
    points: ArrayLike,
    config: PlannerConfig | str | Path | None = None,
    *,
    packed: bool = False,
    support_plane: ArrayLike | None = None,
    seed: int | None = None,
    gripper: GripperModel | None = None,
    camera_positions: ArrayLike | None = None,
) -> PlanResult:
    """The paper's planner: hidden superquadrics (stage one), then ranked grasps (stage two).

    Before both stages the cloud is thinned to 2 mm voxel centroids and isolated points (flying
    pixels) are removed (``cleaning:`` in the config, :mod:`hsqbench.planner.cleaning`; our
    addition): stage two then checks collisions against the cleaned cloud.
    ``hidden_superquadrics[i].inliers`` index ``points`` as given.

    Args:
        points: (N, 3) cloud of the object (or packed scene), world metres, table removed.
        config: a :class:`PlannerConfig`, a config name or a YAML path; None: planner.yaml.
        packed: a packed scene (``h_delta`` left out).
        support_plane: the table ``(a, b, c, d)``, unit normal toward the free side.
        seed: stage one's K-means seed (None = 0: deterministic by default).
        gripper: default: the gripper named in the config.
        camera_positions: (C, 3) camera centres, metres, if known: contacts no camera can see
            then need no support, and rule 6 (hidden bodies) runs (see :func:`plan_from_hidden`).

    Raises:
        ValueError: an empty, non-finite or badly shaped cloud; a bad plane or config.
    """
    context = PlanningContext(
        support_plane=support_plane, packed=packed, seed=seed, camera_positions=camera_positions
    )
    return HSQPlanner(config, gripper).plan(points, context)


class HSQPlanner(PlannerBase):
    """The paper's planner behind the :class:`Planner` protocol.

    ``additions_off``: names of additions (:mod:`hsqbench.planner.additions`) to switch off on
    top of the config's own switches; ``name`` labels the results (e.g. ``hsq-paper``).
    """

    name = "hsq"

    def __init__(
        self,
        config: PlannerConfig | str | Path | None = None,
        gripper: GripperModel | None = None,
        *,
        additions_off: Sequence[str] = (),
        name: str = "hsq",
    ) -> None:
        cfg = resolve_config(config)
        if additions_off:
            unknown = sorted(set(additions_off) - set(AdditionsConfig.names()))
            if unknown:
                raise ValueError(
                    f"unknown addition(s) {unknown}; known: {', '.join(AdditionsConfig.names())}"
                )
            switches = {
                n: getattr(cfg.additions, n) and n not in additions_off
                for n in AdditionsConfig.names()
            }
            cfg = cfg.with_additions(AdditionsConfig(**switches))
        self.config = cfg
        self.name = name
        self.gripper = (
            gripper if gripper is not None else resolve_gripper(self.config.grasp.gripper)
        )

    def cleaning_config(self) -> CleaningConfig:
        return self.config.cleaning

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """Stage one (hidden superquadrics) on the cleaned cloud, or on each object of a packed
        scene (``recovery.split_objects``), then stage two on the whole cloud.

        Stage one's K-means parts are a random draw. When no candidate survives stage two, both
        stages run again on a fresh draw (:func:`redraw_seed`), ``recovery.no_grasp_redraws``
        times at most: where the rules leave a handful of closing lines, another split of the
        cloud into parts often yields the superquadric whose lines survive. A cloud that has
        grasps on the first draw costs no more."""
        rcfg = self.config.recovery
        cloud = clean.points
        # A packed scene is split into objects, each recovered as an isolated one; a cloud
        # whose every cluster is too small is recovered whole.
        groups = object_clusters(cloud, rcfg) if context.packed and rcfg.split_objects else []
        if not groups:
            groups = [np.arange(cloud.shape[0])]
        recovery_s = 0.0
        recoveries: list[Any] = []  # per group, made in the first draw; the draws share seed 0
        for draw in range(rcfg.no_grasp_redraws + 1):
            draw_context = dataclasses.replace(context, seed=redraw_seed(context.seed, draw))
            start = time.perf_counter()
            recoveries = recoveries or self._recoveries(cloud, groups)
            hidden = self._recover(recoveries, groups, clean, draw_context.seed)
            recovery_s += time.perf_counter() - start
            result = plan_in_context(cloud, hidden, self.config.grasp, self.gripper, draw_context)
            if result.grasps:
                break
        if draw > 0 and not result.grasps:
            result.reason += f" (on each of {draw + 1} draws of stage one's K-means parts)"
        result.timings = {"recovery": recovery_s, **result.timings}
        return result

    def _recoveries(self, cloud: NDArray, groups: list[NDArray]) -> list[Any]:
        """Stage one's draw-independent part (:class:`~.recovery.HiddenRecovery`) per group."""
        from hsqbench.planner.recovery import HiddenRecovery

        return [HiddenRecovery(cloud[group], self.config.recovery) for group in groups]

    def _recover(
        self, recoveries: list[Any], groups: list[NDArray], clean: CleanInput, seed: int | None
    ) -> list[Any]:
        """Stage one's draw ``seed`` on each group; inliers index the caller's cloud."""
        # A loop over objects (at most a handful), each recovery vectorised over its points.
        hidden = [
            dataclasses.replace(h, inliers=group[h.inliers])
            for group, recovery in zip(groups, recoveries, strict=True)
            for h in recovery.draw(seed)
        ]
        return [dataclasses.replace(h, inliers=clean.input_indices(h.inliers)) for h in hidden]


def redraw_seed(seed: int | None, draw: int) -> int | None:
    """The planner seed of draw ``draw`` (0: ``seed`` itself) of :meth:`HSQPlanner.stages`:
    later draws get independent seeds derived from ``seed`` and the draw's number."""
    if draw == 0:
        return seed
    return int(np.random.SeedSequence([0 if seed is None else seed, draw]).generate_state(1)[0])
