"""The learning-free grasp planner of the paper, in two stages.

Stage one (:mod:`hsqbench.planner.recovery`) recovers hidden superquadrics from a point cloud;
stage two (synthesis, elimination, scoring) turns them into ranked antipodal grasps. The whole
planner is :func:`plan_grasps`; harness code talks to any planner through :class:`Planner`.

Names are resolved lazily so that importing one stage does not import the other.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "FitResult": "hsqbench.planner.recovery",
    "HiddenSuperquadric": "hsqbench.planner.recovery",
    "fit_superquadric": "hsqbench.planner.recovery",
    "recover_hidden_superquadrics": "hsqbench.planner.recovery",
    "PlannerConfig": "hsqbench.planner.config",
    "RecoveryConfig": "hsqbench.planner.config",
    "GraspConfig": "hsqbench.planner.config",
    "load_planner_config": "hsqbench.planner.config",
    "Grasp": "hsqbench.planner.grasp",
    "GripperModel": "hsqbench.planner.gripper",
    "PlanResult": "hsqbench.planner.api",
    "PlanningContext": "hsqbench.planner.api",
    "Planner": "hsqbench.planner.api",
    "plan_grasps": "hsqbench.planner.api",
    "plan_from_hidden": "hsqbench.planner.api",
    "HSQPlanner": "hsqbench.planner.api",
    "PlannerBase": "hsqbench.planner.base",
    "CleanInput": "hsqbench.planner.base",
    "register_planner": "hsqbench.planner.registry",
    "get_planner": "hsqbench.planner.registry",
    "planner_names": "hsqbench.planner.registry",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    if name not in _EXPORTS:
        raise AttributeError(f"module 'hsqbench.planner' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)
