"""Stage two of the paper's planner as one call: grasps from given hidden superquadrics.

:func:`plan_from_hidden` runs synthesis (paper Sec. III-B2, :mod:`.synthesis`, with the table
lines of :mod:`.table_lines`), elimination (Sec. III-B2, :mod:`.elimination`) and scoring
(Sec. III-B3, Eq. 5-11, :mod:`.scoring`) on hidden superquadrics, e.g. stage one's, or known shapes in tests;
:func:`plan_in_context` is the same with the scene facts of a
:class:`~hsqbench.planner.api.PlanningContext`: the stage every superquadric planner (hsq,
single-sq) ends with.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from hsqbench.planner.api import (
    PlanningContext,
    PlanResult,
    validate_cameras,
    validate_cloud,
    validate_plane,
)
from hsqbench.planner.base import rules_removed_reason
from hsqbench.planner.gripper import GripperModel, resolve_gripper
from hsqbench.planner.hsq.config import GraspConfig, resolve_config
from hsqbench.planner.hsq.stage_two.candidates import REJECTION_REASONS, CandidateSet
from hsqbench.planner.hsq.stage_two.elimination import eliminate
from hsqbench.planner.hsq.stage_two.hidden_bodies import body_obstacles
from hsqbench.planner.hsq.stage_two.scoring import fit_factors, score_candidates
from hsqbench.planner.hsq.stage_two.synthesis import synthesize
from hsqbench.planner.hsq.stage_two.table_lines import level_table_lines
from hsqbench.superquadric.geometry import Superquadric


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
            blocks are levelled and lifted first (:mod:`hsqbench.planner.hsq.stage_two.table_lines`).
        seed: for the subset used to estimate the cloud's spacing (None = 0).
        camera_positions: (C, 3) camera centres, metres; with them, contacts no camera can see
            need no support (``grasp.unseen_incidence_deg``), and rule 6 keeps the hand out of
            the hidden superquadrics where no camera saw free space, in place of the support
            rule's facing test (:mod:`hsqbench.planner.hsq.stage_two.hidden_bodies`). None: every contact
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
