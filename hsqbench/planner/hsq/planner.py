"""The paper's planner, hsq: stage one (:mod:`hsqbench.planner.hsq.stage_one`, hidden
superquadrics) then stage two (:mod:`hsqbench.planner.hsq.stage_two`, ranked antipodal grasps),
behind the :class:`~hsqbench.planner.api.Planner` protocol (:class:`HSQPlanner`) and as one
function (:func:`plan_grasps`); our additions to the paper are switched by
:mod:`hsqbench.planner.hsq.additions`.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import PlanningContext, PlanResult
from hsqbench.planner.base import CleanInput, PlannerBase
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.gripper import GripperModel, resolve_gripper
from hsqbench.planner.hsq.additions import AdditionsConfig
from hsqbench.planner.hsq.config import PlannerConfig, resolve_config
from hsqbench.planner.hsq.stage_one.clusters import object_clusters
from hsqbench.planner.hsq.stage_one.recovery import HiddenRecovery
from hsqbench.planner.hsq.stage_two.plan import plan_in_context


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

    ``additions_off``: names of additions (:mod:`hsqbench.planner.hsq.additions`) to switch off on
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
        recoveries: list[HiddenRecovery] = []  # per group, made once: the draws share seed 0
        for draw in range(rcfg.no_grasp_redraws + 1):
            draw_context = dataclasses.replace(context, seed=redraw_seed(context.seed, draw))
            start = time.perf_counter()
            recoveries = recoveries or [HiddenRecovery(cloud[g], rcfg) for g in groups]
            hidden = self._recover(recoveries, groups, clean, draw_context.seed)
            recovery_s += time.perf_counter() - start
            result = plan_in_context(cloud, hidden, self.config.grasp, self.gripper, draw_context)
            if result.grasps:
                break
        if draw > 0 and not result.grasps:
            result.reason += f" (on each of {draw + 1} draws of stage one's K-means parts)"
        result.timings = {"recovery": recovery_s, **result.timings}
        return result

    def _recover(
        self,
        recoveries: list[HiddenRecovery],
        groups: list[NDArray],
        clean: CleanInput,
        seed: int | None,
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
