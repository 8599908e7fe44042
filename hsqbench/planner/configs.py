"""Each planner's config, in one tree (``planners:`` of ``configs/trial.yaml``): every planner
reads its own config type, never another planner's."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from hsqbench.planner.baselines.config import BaselinesConfig
from hsqbench.planner.hsq.config import PlannerConfig
from hsqbench.planner.learned.config import ContactGraspNetConfig
from hsqbench.planner.oracle import OracleConfig


@dataclass(frozen=True)
class PlannerConfigs:
    """Attributes (each a config name in ``configs/`` or its mapping):
    hsq: ``PlannerConfig`` of hsq and its ablations (``configs/planner.yaml``).
    baselines: ``BaselinesConfig`` of single-sq and antipodal (``configs/baselines.yaml``).
    oracle: ``OracleConfig`` of the privileged oracle planner (``configs/oracle.yaml``).
    contact_graspnet: ``ContactGraspNetConfig`` of both contact-graspnet planners.
    """

    hsq: PlannerConfig = field(default_factory=PlannerConfig)
    baselines: BaselinesConfig = field(default_factory=BaselinesConfig)
    oracle: OracleConfig = field(default_factory=OracleConfig)
    contact_graspnet: ContactGraspNetConfig = field(default_factory=ContactGraspNetConfig)

    def for_planner(self, name: str) -> Any:
        """The config planner ``name`` is built with (None: one registered without a config
        entry here, which then uses its own default)."""
        from hsqbench.planner.registry import planner_config_key

        key = planner_config_key(name)
        return None if key is None else getattr(self, key)
