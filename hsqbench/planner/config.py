"""Planner configuration: ``configs/planner.yaml`` loaded into typed, frozen dataclasses.

Two sections, one per stage: ``recovery`` (stage one) and ``grasp`` (stage two). Every default
here is mirrored, with its reason, in ``configs/planner.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from hsqbench.config import load_config


@dataclass(frozen=True)
class RecoveryConfig:
    """Stage one: hidden superquadric recovery (owned by ``hsqbench.planner.recovery``)."""


@dataclass(frozen=True)
class GraspConfig:
    """Stage two: grasp synthesis, elimination and scoring."""


@dataclass(frozen=True)
class PlannerConfig:
    recovery: RecoveryConfig = field(default_factory=RecoveryConfig)
    grasp: GraspConfig = field(default_factory=GraspConfig)


def load_planner_config(path: str | Path | None = "planner") -> PlannerConfig:
    """Load ``configs/planner.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(PlannerConfig, path)
