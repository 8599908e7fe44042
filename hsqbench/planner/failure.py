"""A planner's own failure: an exception from its code, or output its contract rules out.

The harness asks a planner for grasps through :func:`checked_plan`. Whatever goes wrong inside
that call is the planner's failure, not the harness's: an exception, a result that is not a
:class:`~hsqbench.planner.api.PlanResult`, a grasp that is not a valid
:class:`~hsqbench.planner.grasp.Grasp` (a NaN or infinite pose, a rotation that is not one, a
negative width, a NaN score). Each becomes a :class:`PlannerError`, one line naming the planner,
the line of its code where it happened (the deepest frame in the planner's own files; for an
invalid grasp, the line that built it) and the contract it broke. The trial runner records it as
a ``planner_error`` attempt, a failed attempt of that planner in GSR and CR
(:mod:`hsqbench.sim.trial.attempt`); ``hsqbench trial`` and ``hsqbench plan`` print it and exit 2.
"""

from __future__ import annotations

import inspect
import numbers
import os
import sys
import traceback
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from hsqbench.planner.grasp import Grasp, InvalidGrasp

#: Where the contract is written down; every message points there.
CONTRACT_DOC = "docs/your-own-planner.md"
#: A message longer than this is cut (it goes into one CSV cell).
MESSAGE_CHARS = 600
_GRASP_FILE = os.path.normcase(os.path.abspath(inspect.getfile(Grasp)))


class PlannerError(ValueError):
    """A planner raised or broke its output contract (the message is one line: the planner,
    its file and line, what went wrong)."""


def one_line(text: str, limit: int = MESSAGE_CHARS) -> str:
    """``text`` on one line (its lines joined by `` | ``), cut to ``limit`` characters."""
    text = " | ".join(part.strip() for part in text.strip().splitlines() if part.strip())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def planner_name(planner: Any) -> str:
    name = getattr(planner, "name", None)
    return name if isinstance(name, str) and name else type(planner).__name__


def _shown(path: str) -> str:
    """``path`` relative to the current folder when it is below it (as the user typed it)."""
    try:
        rel = os.path.relpath(path)
    except ValueError:  # another drive
        return path
    return path if rel.startswith("..") else rel


def _code_root(owner: Any) -> str | None:
    """The code of ``owner`` (a planner, its class or its factory function): its top-level
    package's folder, or its module's file."""
    name = str(getattr(owner, "__module__", None) or type(owner).__module__)
    module = sys.modules.get(name)
    top = sys.modules.get(name.partition(".")[0], module)
    file = getattr(top, "__file__", None)
    if not file:
        return None
    path = Path(file).resolve()
    return os.path.normcase(str(path.parent if path.name == "__init__.py" else path))


def _own(filename: str, root: str | None) -> bool:
    if root is None:
        return False
    path = os.path.normcase(os.path.abspath(filename))
    return path == root or path.startswith(root + os.sep)


def location(exc: BaseException, planner: Any, own_only: bool = False) -> str | None:
    """``file:line`` of the planner's code where ``exc`` happened: the deepest frame in the
    planner's own files (else the deepest frame, or None with ``own_only``), skipping, for an
    invalid grasp, the :class:`Grasp` checks themselves so that the line that built the grasp
    is named. ``planner``: the planner, its class or its factory function."""
    frames = list(traceback.extract_tb(exc.__traceback__))
    if isinstance(exc, InvalidGrasp):
        while frames and (
            os.path.normcase(os.path.abspath(frames[-1].filename)) == _GRASP_FILE
            or frames[-1].filename.startswith("<")  # the dataclass's generated __init__
        ):
            frames.pop()
    root = _code_root(planner)
    own = [f for f in frames if _own(f.filename, root)]
    frame = own[-1] if own else (None if own_only or not frames else frames[-1])
    if frame is None:
        return None if own_only else "an unknown line"
    return f"{_shown(frame.filename)}:{frame.lineno}"


def _method_location(planner: Any, method: str) -> str:
    """``file:line`` where the planner's ``method`` is defined."""
    try:
        func = inspect.unwrap(getattr(type(planner), method))
        return f"{_shown(inspect.getsourcefile(func) or '?')}:{inspect.getsourcelines(func)[1]}"
    except (AttributeError, TypeError, OSError):
        return f"{type(planner).__name__}.{method}"


def from_exception(planner: Any, exc: Exception) -> PlannerError:
    """The :class:`PlannerError` of an exception raised in the planner's call."""
    name, where = planner_name(planner), location(exc, planner)
    if isinstance(exc, InvalidGrasp):
        what = f"built an invalid Grasp at {where}: {exc}"
    else:
        what = (
            f"raised {type(exc).__name__} at {where}: {exc} (a planner returns a PlanResult, "
            "with no grasp and a reason when it finds none, and does not raise)"
        )
    return PlannerError(one_line(f"planner {name!r} {what}; see {CONTRACT_DOC}"))


def check_result(planner: Any, result: Any, method: str) -> None:
    """Raise :class:`PlannerError` unless ``result`` (what the planner's ``method`` returned)
    is a PlanResult whose grasps are :class:`Grasp` records, with timings in seconds."""
    from hsqbench.planner.api import PlanResult

    def broke(what: str) -> PlannerError:
        where = _method_location(planner, method)
        return PlannerError(
            one_line(
                f"planner {planner_name(planner)!r}: {method} at {where} {what}; see {CONTRACT_DOC}"
            )
        )

    if not isinstance(result, PlanResult):
        raise broke(
            f"returned {type(result).__name__}, not a PlanResult (wrap the grasps: "
            "PlanResult(grasps=[...]))"
        )
    grasps = result.grasps
    if not (hasattr(grasps, "__len__") and hasattr(grasps, "__getitem__")):
        raise broke(f"returned grasps as {type(grasps).__name__}, not a list of Grasp")
    if isinstance(grasps, list | tuple):  # a lazy sequence (hsq's) is the harness's own
        bad = next((i for i, g in enumerate(grasps) if not isinstance(g, Grasp)), None)
        if bad is not None:
            raise broke(f"returned grasps[{bad}] as {type(grasps[bad]).__name__}, not a Grasp")
        # A Grasp may be unscored (NaN) inside a planner; what it returns is ranked by score.
        bad = next((i for i, g in enumerate(grasps) if np.isnan(g.score)), None)
        if bad is not None:
            raise broke(
                f"returned grasps[{bad}] with score NaN (grasp score must be a number: the "
                "harness ranks grasps by score)"
            )
    timings = result.timings
    if not isinstance(timings, Mapping) or not all(
        isinstance(v, numbers.Real) and not isinstance(v, bool) for v in timings.values()
    ):
        raise broke("returned timings that are not a mapping of stage names to seconds")
    if not isinstance(result.reason, str):
        raise broke(f"returned a reason of type {type(result.reason).__name__}, not text")


def checked_plan(planner: Any, points: Any, context: Any) -> Any:
    """``planner.plan(points, context)``, its result checked (:func:`check_result`).

    Raises:
        PlannerError: the planner raised (MemoryError aside: the machine's, not the planner's)
            or broke its contract.
    """
    try:
        result = planner.plan(points, context)
    except PlannerError:
        raise
    except MemoryError:
        raise
    except Exception as exc:
        raise from_exception(planner, exc) from exc
    check_result(planner, result, "plan")
    return result
