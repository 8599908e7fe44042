"""The harness's elimination rules for any planner's own grasps (opt in with
:meth:`~hsqbench.planner.base.PlannerBase.apply_rules`).

The grasps go through the rules hsq's candidates go through (duplicate, width, support, table,
collision, approach sweep; :mod:`hsqbench.planner.elimination`) with hsq's stage-two settings and
gripper (``grasp:`` of ``configs/planner.yaml``), the table and cameras of the context; the
survivors are ranked by the planner's own scores. This is what ``contact-graspnet-elim`` does to
the network's grasps: a planner compared with and without the rules shows what they buy.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from hsqbench.planner.base import CleanInput, rules_removed_reason
from hsqbench.planner.candidates import REJECTION_REASONS, CandidateSet, ClosingLines
from hsqbench.planner.elimination import eliminate
from hsqbench.planner.grasp import Grasp

if TYPE_CHECKING:
    from hsqbench.planner.api import PlanningContext, PlanResult
    from hsqbench.planner.config import GraspConfig

#: ``Grasp.family`` of grasps that went through the rules here.
FAMILY = "own"


def apply_rules(
    grasps: Sequence[Grasp],
    clean: CleanInput,
    context: PlanningContext,
    config: GraspConfig | None = None,
) -> PlanResult:
    """``grasps`` less those a rule removes, best score first, with the counts per rule.

    Args:
        grasps: the planner's grasps (world frame, :mod:`hsqbench.planner.grasp`).
        clean: the cleaned cloud the planner was given (collisions are checked against it).
        context: the table (``support_plane``) and the cameras (a contact none of them sees
            needs no support), as for hsq.
        config: stage-two settings; default: ``grasp:`` of ``configs/planner.yaml``.
    """
    from hsqbench.planner.api import (
        PlanResult,
        resolve_config,
        resolve_gripper,
        validate_cameras,
        validate_plane,
    )

    start = time.perf_counter()
    cfg = config if config is not None else resolve_config(None).grasp
    n = len(grasps)
    if n == 0:
        return PlanResult(grasps=[], reason="the planner proposed no grasp")
    rotations = np.stack([g.rotation for g in grasps])
    lines = ClosingLines(
        centres=np.stack([g.position for g in grasps]),
        directions=rotations[:, :, 0],
        approach0=rotations[:, :, 2],
        half_lengths=0.5 * np.array([g.width for g in grasps]),
        source=np.full(n, -1, dtype=np.int64),
        axis=np.full(n, -1, dtype=np.int64),
        family=np.full(n, FAMILY, dtype="<U12"),
    )
    cands = CandidateSet(lines, np.zeros(1))
    seed = 0 if context.seed is None else int(context.seed)
    report = eliminate(
        cands,
        clean.points,
        resolve_gripper(cfg.gripper),
        cfg,
        validate_plane(context.support_plane),
        seed,
        camera_positions=validate_cameras(context.camera_positions),
    )
    kept = cands.kept
    cands.scores = np.where(kept, np.array([g.score for g in grasps]), np.nan)
    ranked = cands.ranked()
    counts = cands.counts_by_reason()
    reason = ""
    if not ranked:
        reason = rules_removed_reason(counts, f"the rules removed all {n} grasps: ")
    return PlanResult(
        grasps=ranked,
        candidates=cands,
        remaining=report.remaining,
        removed_by={r: counts[r] for r in REJECTION_REASONS},
        timings={"elimination": time.perf_counter() - start},
        reason=reason,
    )
