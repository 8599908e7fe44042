"""The ``single-sq`` baseline: one superquadric for the whole object, grasps along its axes.

This is the single-superquadric grasping that the paper improves on (Vezzani et al. 2017,
Makhal et al. 2018): stage one is :func:`~hsqbench.planner.hsq.stage_one.recovery.fit_superquadric` on the
whole (downsampled) cloud with the low, single-object outlier weight
(``recovery.outlier_weight`` of the planner config), instead of the K + 1 hidden superquadrics;
stage two is the hsq planner's own synthesis, elimination and scoring
(:func:`~hsqbench.planner.hsq.stage_two.plan.plan_from_hidden`) on that one superquadric, with its inliers
(posterior > ``recovery.inlier_threshold``) and the paper's alpha and beta on them. As for hsq,
isolated points are removed first (``cleaning:`` of the planner config) and the cameras, when
known, waive support at contacts none of them sees.

On a shape one superquadric describes (a box, a cylinder) it plans like hsq; on a composite
shape (an L, a mug with a handle) the one superquadric envelops the parts, its axes cross air
and its alpha is large, which is the failure the paper's hidden superquadrics address.

In packed scenes the method needs one cloud per object, as the single-superquadric papers
segment theirs: the cloud is split into Euclidean clusters
(:func:`~hsqbench.planner.hsq.stage_one.clusters.object_clusters` with the planner config's ``recovery:``
settings, as hsq's stage one; objects are placed apart) and each cluster gets its own
superquadric. Isolated clouds are one object.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import PlanningContext, PlanResult
from hsqbench.planner.base import CleanInput
from hsqbench.planner.baselines.config import BaselinesConfig
from hsqbench.planner.baselines.planner import BaselinePlanner
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import RecoveryConfig
from hsqbench.planner.hsq.stage_one.clusters import object_clusters
from hsqbench.planner.hsq.stage_one.recovery import (
    HiddenSuperquadric,
    fit_measures,
    fit_superquadric,
)
from hsqbench.planner.hsq.stage_two.plan import plan_in_context


def _one_superquadric(
    cloud: NDArray[np.float64], members: NDArray[np.int64], index: int, rcfg: RecoveryConfig
) -> HiddenSuperquadric:
    """``fit_superquadric`` on ``cloud[members]``; inliers index ``cloud``."""
    fit = fit_superquadric(cloud[members], config=rcfg)
    inliers = members[fit.inlier_probability > rcfg.inlier_threshold]
    sq = fit.superquadric
    if inliers.size:
        alpha, beta = fit_measures(cloud[inliers], sq, rcfg)
    else:
        alpha, beta = float("inf"), 0.0
    return HiddenSuperquadric(sq, inliers, alpha, beta, index, fit.sigma_m, fit.cost)


def plan_single_sq(
    points: ArrayLike,
    config: BaselinesConfig | str | Path | None = None,
    *,
    packed: bool = False,
    support_plane: ArrayLike | None = None,
    seed: int | None = None,
    gripper: GripperModel | None = None,
    camera_positions: ArrayLike | None = None,
) -> PlanResult:
    """One superquadric fitted to the whole (cleaned) cloud, or to each object of a packed
    scene, then the hsq planner's stage two.

    Args:
        points: (N, 3) cloud of the object, world metres, table removed.
        config: a :class:`BaselinesConfig`, a config name or a YAML path; None: baselines.yaml
            (whose ``planner`` entry names the stage-one and stage-two settings).
        packed: a packed scene: ``h_delta`` left out, and one superquadric per object
            (:func:`~hsqbench.planner.hsq.stage_one.clusters.object_clusters`).
        support_plane: the table ``(a, b, c, d)``, unit normal toward the free side.
        seed: passed to stage two (the fit itself is deterministic).
        gripper: default: the gripper of the planner config's ``grasp:`` section.
        camera_positions: (C, 3) camera centres, metres, if known: contacts no camera can see
            then need no support, as for hsq (:func:`~hsqbench.planner.hsq.stage_two.plan.plan_from_hidden`).

    Raises:
        ValueError: a cloud :func:`fit_superquadric` refuses (empty, NaN, too few points,
            collinear); a bad plane, camera array or config.

    ``hidden_superquadrics`` of the result holds the fitted superquadric (one per object in
    packed scenes, largest object first); their inliers index ``points`` as given.
    """
    context = PlanningContext(
        support_plane=support_plane, packed=packed, seed=seed, camera_positions=camera_positions
    )
    return SingleSQPlanner(config, gripper).plan(points, context)


class SingleSQPlanner(BaselinePlanner):
    """The single-superquadric baseline behind the :class:`~hsqbench.planner.api.Planner`
    protocol."""

    name = "single-sq"

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """One superquadric per object (the whole cloud when not packed), then stage two."""
        pcfg = self.planner_config
        cloud = clean.points
        rcfg = pcfg.recovery
        start_recovery = time.perf_counter()
        whole = [np.arange(cloud.shape[0])]
        groups = object_clusters(cloud, rcfg) if context.packed else whole
        # A loop over objects (at most a handful), each fit vectorised over its points.
        fits = [_one_superquadric(cloud, g, i, rcfg) for i, g in enumerate(groups)]
        # Inliers index the caller's cloud, not the cleaned one (as hsq's).
        hidden = [dataclasses.replace(h, inliers=clean.input_indices(h.inliers)) for h in fits]
        t_recovery = time.perf_counter() - start_recovery
        if not hidden:
            result = PlanResult(
                grasps=[],
                timings={},
                reason=(
                    f"no object: every cluster of the cleaned cloud has fewer than "
                    f"{rcfg.min_cluster_points} points (recovery.min_cluster_points)"
                ),
            )
        else:
            result = plan_in_context(cloud, hidden, pcfg.grasp, self.gripper, context)
        result.timings = {"recovery": t_recovery, **result.timings}
        return result
