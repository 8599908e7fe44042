"""hsqbench: a MuJoCo benchmark for learning-free grasping with hidden superquadrics.

The Python API (:mod:`hsqbench.runs`, loaded on first use): :func:`run_trial`,
:func:`run_benchmark` and :func:`load_run` do what ``hsqbench trial``, ``hsqbench benchmark``
and the report read, with pandas frames of a run's attempts and rounds.
"""

import importlib
from typing import Any

__version__ = "0.1.0"

_API = ("run_trial", "run_benchmark", "load_run", "RunData")
__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    if name in _API:  # resolved on first use, as in hsqbench.planner: `import hsqbench` stays light
        return getattr(importlib.import_module("hsqbench.runs"), name)
    raise AttributeError(f"module 'hsqbench' has no attribute {name!r}")
