"""The wiring every baseline shares behind the :class:`~hsqbench.planner.api.Planner` protocol
(the front door itself, with the cleaning shared with hsq, is :mod:`hsqbench.planner.base`)."""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from hsqbench.planner.base import CleanInput, PlannerBase, clean_input
from hsqbench.planner.baselines.config import BaselinesConfig, resolve_baselines_config
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.gripper import GripperModel, resolve_gripper
from hsqbench.planner.hsq.config import PlannerConfig, resolve_config

__all__ = ["BaselinePlanner", "CleanInput", "clean_input"]


class BaselinePlanner(PlannerBase):
    """A baseline with its config, the planner config it shares with hsq (cleaning, stage-two
    settings: ``planner`` of the baselines config) and its gripper resolved once.

    Subclasses set ``name`` and :meth:`~hsqbench.planner.base.PlannerBase.stages`. The gripper
    defaults to the one named by that planner config. The context reaches the baselines as it
    reaches hsq, whole: the table, the packed flag, the seed and the cameras.
    """

    name: ClassVar[str]

    def __init__(
        self,
        config: BaselinesConfig | str | Path | None = None,
        gripper: GripperModel | None = None,
    ) -> None:
        self.config = resolve_baselines_config(config)
        self.planner_config: PlannerConfig = resolve_config(self.config.planner)
        grasp = self.planner_config.grasp
        self.gripper = gripper if gripper is not None else resolve_gripper(grasp.gripper)

    def cleaning_config(self) -> CleaningConfig:
        return self.planner_config.cleaning
