"""Grasp planners behind one contract, and the learning-free planner of the paper.

The contract every planner shares: :mod:`.api` (:class:`Planner`, :class:`PlanningContext`,
:class:`PlanResult`, input checks), :mod:`.base` (the front door: validate, clean, time),
:mod:`.registry` (planners by name), :mod:`.grasp`, :mod:`.gripper`, :mod:`.cleaning`.
The planners: :mod:`.hsq` (the paper's, in two stages: :mod:`.hsq.stage_one` recovers hidden
superquadrics from a point cloud, :mod:`.hsq.stage_two` turns them into ranked antipodal
grasps), :mod:`.baselines`, :mod:`.learned` and :mod:`.oracle`. The whole hsq planner is
:func:`plan_grasps`; harness code talks to any planner through :class:`Planner`.

Names are resolved lazily so that importing one stage does not import the other.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "FitResult": "hsqbench.planner.hsq.stage_one.recovery",
    "HiddenSuperquadric": "hsqbench.planner.hsq.stage_one.recovery",
    "fit_superquadric": "hsqbench.planner.hsq.stage_one.recovery",
    "recover_hidden_superquadrics": "hsqbench.planner.hsq.stage_one.recovery",
    "PlannerConfig": "hsqbench.planner.hsq.config",
    "RecoveryConfig": "hsqbench.planner.hsq.config",
    "GraspConfig": "hsqbench.planner.hsq.config",
    "load_planner_config": "hsqbench.planner.hsq.config",
    "Grasp": "hsqbench.planner.grasp",
    "GripperModel": "hsqbench.planner.gripper",
    "PlanResult": "hsqbench.planner.api",
    "PlanningContext": "hsqbench.planner.api",
    "Planner": "hsqbench.planner.api",
    "plan_grasps": "hsqbench.planner.hsq.planner",
    "plan_from_hidden": "hsqbench.planner.hsq.stage_two.plan",
    "HSQPlanner": "hsqbench.planner.hsq.planner",
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
