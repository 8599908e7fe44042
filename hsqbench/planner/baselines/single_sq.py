"""The ``single-sq`` baseline: one superquadric for the whole object, grasps along its axes.

This is the single-superquadric grasping that the paper improves on (Vezzani et al. 2017,
Makhal et al. 2018): stage one is :func:`~hsqbench.planner.recovery.fit_superquadric` on the
whole (downsampled) cloud with the low, single-object outlier weight
(``recovery.outlier_weight`` of the planner config), instead of the K + 1 hidden superquadrics;
stage two is the hsq planner's own synthesis, elimination and scoring
(:func:`~hsqbench.planner.api.plan_from_hidden`) on that one superquadric, with its inliers
(posterior > ``recovery.inlier_threshold``) and the paper's alpha and beta on them. As for hsq,
isolated points are removed first (``cleaning:`` of the planner config) and the cameras, when
known, waive support at contacts none of them sees.

On a shape one superquadric describes (a box, a cylinder) it plans like hsq; on a composite
shape (an L, a mug with a handle) the one superquadric envelops the parts, its axes cross air
and its alpha is large, which is the failure the paper's hidden superquadrics address.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from hsqbench.planner.api import PlanResult, plan_from_hidden, resolve_config
from hsqbench.planner.baselines.config import BaselinesConfig, resolve_baselines_config
from hsqbench.planner.baselines.planner import BaselinePlanner, clean_input
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.recovery import HiddenSuperquadric, fit_measures, fit_superquadric


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
    """One superquadric fitted to the whole (cleaned) cloud, then the hsq planner's stage two.

    Args:
        points: (N, 3) cloud of the object, world metres, table removed.
        config: a :class:`BaselinesConfig`, a config name or a YAML path; None: baselines.yaml
            (whose ``planner`` entry names the stage-one and stage-two settings).
        packed: a packed scene (``h_delta`` left out); one superquadric for several objects is
            the baseline's own weakness, not an error.
        support_plane: the table ``(a, b, c, d)``, unit normal toward the free side.
        seed: passed to stage two (the fit itself is deterministic).
        gripper: default: the gripper of the planner config's ``grasp:`` section.
        camera_positions: (C, 3) camera centres, metres, if known: contacts no camera can see
            then need no support, as for hsq (:func:`~hsqbench.planner.api.plan_from_hidden`).

    Raises:
        ValueError: a cloud :func:`fit_superquadric` refuses (empty, NaN, too few points,
            collinear); a bad plane, camera array or config.

    ``hidden_superquadrics`` of the result holds the one fitted superquadric; its inliers
    index ``points`` as given.
    """
    start = time.perf_counter()
    pcfg = resolve_config(resolve_baselines_config(config).planner)
    clean = clean_input(points, pcfg.cleaning)
    if clean.points.shape[0] == 0:
        return clean.empty_result(pcfg.cleaning, SingleSQPlanner.name)
    cloud = clean.points
    rcfg = pcfg.recovery
    start_recovery = time.perf_counter()
    fit = fit_superquadric(cloud, config=rcfg)
    inliers = np.flatnonzero(fit.inlier_probability > rcfg.inlier_threshold)
    sq = fit.superquadric
    if inliers.size:
        alpha, beta = fit_measures(cloud[inliers], sq, rcfg)
    else:
        alpha, beta = float("inf"), 0.0
    # Inliers index the caller's cloud, not the cleaned one (as hsq's).
    hidden = HiddenSuperquadric(sq, clean.kept[inliers], alpha, beta, 0, fit.sigma_m, fit.cost)
    t_recovery = time.perf_counter() - start_recovery
    result = plan_from_hidden(
        cloud,
        [hidden],
        pcfg.grasp,
        gripper=gripper,
        packed=packed,
        support_plane=support_plane,
        seed=seed,
        camera_positions=camera_positions,
    )
    result.planner = SingleSQPlanner.name
    result.n_removed = clean.n_removed
    result.timings = {"cleaning": clean.seconds, "recovery": t_recovery, **result.timings}
    result.timings["total"] = time.perf_counter() - start
    return result


class SingleSQPlanner(BaselinePlanner):
    """The single-superquadric baseline behind the :class:`~hsqbench.planner.api.Planner`
    protocol."""

    name = "single-sq"
    plan_function = staticmethod(plan_single_sq)
