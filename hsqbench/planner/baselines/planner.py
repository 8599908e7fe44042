"""The wiring every baseline shares behind the :class:`~hsqbench.planner.api.Planner` protocol."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import ClassVar

from numpy.typing import ArrayLike

from hsqbench.planner.api import PlanningContext, PlanResult, resolve_config, resolve_gripper
from hsqbench.planner.baselines.config import BaselinesConfig, resolve_baselines_config
from hsqbench.planner.gripper import GripperModel


class BaselinePlanner:
    """A baseline's plan function with its config and gripper resolved once.

    Subclasses set ``name`` and ``plan_function``, a callable with the signature of
    ``plan_single_sq``: ``(points, config, *, packed, support_plane, seed, gripper)``.
    The gripper defaults to the one named by the planner config the baselines share with hsq.
    """

    name: ClassVar[str]
    plan_function: ClassVar[Callable[..., PlanResult]]

    def __init__(
        self,
        config: BaselinesConfig | str | Path | None = None,
        gripper: GripperModel | None = None,
    ) -> None:
        self.config = resolve_baselines_config(config)
        grasp = resolve_config(self.config.planner).grasp
        self.gripper = gripper if gripper is not None else resolve_gripper(grasp.gripper)

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult:
        return type(self).plan_function(
            points,
            self.config,
            packed=context.packed,
            support_plane=context.support_plane,
            seed=context.seed,
            gripper=self.gripper,
        )
