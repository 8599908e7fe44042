"""Planners from outside this repository: an installed package's entry point, or a spec.

Two ways in, neither touching hsqbench:

- **An installed package** declares an entry point in the group ``hsqbench.planners``; its name is
  the planner's name::

      [project.entry-points."hsqbench.planners"]
      mine = "mypkg.planner:Mine"

- **A spec** where a planner name goes (``--planner``, ``--planners``, the Python API):
  ``module:Attr`` (a module on ``sys.path`` or in the current folder) or ``path/to/file.py:Attr``.
  The planner's name is ``Attr.name`` when that is a string, else ``Attr``.

``Attr`` is a planner class (built with no argument, or with the config given to
:func:`~hsqbench.planner.registry.get_planner`) or a function returning a planner. Worker
processes resolve entry points themselves; a spec travels to them with the run
(:class:`~hsqbench.experiment.backend.SimBackend` carries the specs registered in
:mod:`~hsqbench.planner.registry`), and :class:`PlannerSource` says where each planner's code
came from (module, version, file hash) for the run's identity. This module loads; the registry
registers.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import os
import sys
from dataclasses import asdict, dataclass
from importlib import metadata
from pathlib import Path
from typing import Any

from hsqbench.names import near

ENTRY_POINT_GROUP = "hsqbench.planners"


class PluginError(ValueError):
    """A plugin planner cannot be found, imported or built (one line: what and the fix)."""


@dataclass(frozen=True)
class PlannerSource:
    """Where a planner's code comes from (recorded in a run's ``run.json`` and config hash).

    Attributes:
        kind: ``entry-point``, ``module`` or ``file``.
        spec: ``module:Attr``, or an absolute ``path.py:Attr``.
        module: the module the planner lives in.
        distribution, version: the installed package that provides it (None for a file or a
            module that no installed package owns).
        file: that module's source file; sha256: its hash (None without a file).
    """

    kind: str
    spec: str
    module: str
    distribution: str | None = None
    version: str | None = None
    file: str | None = None
    sha256: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def is_spec(text: str) -> bool:
    """Whether ``text`` is a ``module:Attr`` or ``file.py:Attr`` spec rather than a name."""
    return ":" in text


def _file_hash(path: str | None) -> str | None:
    if path is None or not os.path.isfile(path):
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def _import_file(path: Path) -> Any:
    """Import ``path`` as a module named after its content's location (so that two files of
    the same name do not collide); it is put in ``sys.modules`` as dataclasses need."""
    resolved = path.resolve()
    digest = hashlib.sha256(str(resolved).encode()).hexdigest()[:10]
    name = f"hsqbench_plugin_{resolved.stem}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, resolved)
    if spec is None or spec.loader is None:
        raise PluginError(f"cannot import {path}: not a Python file")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _import_module(name: str) -> Any:
    # The current folder is searched too, as `python -m` does (the `hsqbench` script does not).
    if "" not in sys.path and os.getcwd() not in sys.path:
        sys.path.append(os.getcwd())
    return importlib.import_module(name)


def _is_file(target: str) -> bool:
    return target.endswith(".py") or "/" in target or os.sep in target


def load_spec(spec: str) -> tuple[Any, PlannerSource]:
    """The object a spec names and where it comes from.

    Raises:
        PluginError: a malformed spec, a missing file or module, an import that fails, or no
            such attribute (with the module's planner-like names as suggestions).
    """
    target, _, attr = spec.rpartition(":")
    if not target or not attr.isidentifier():
        raise PluginError(
            f"planner spec {spec!r} must be module:Name or path/to/file.py:Name (e.g. "
            "examples/topdown.py:TopDown)"
        )
    try:
        if _is_file(target):
            path = Path(target)
            if not path.is_file():
                raise PluginError(f"planner spec {spec!r}: no file {path} (from {os.getcwd()})")
            module = _import_file(path)
            kind, full = "file", f"{path.resolve()}:{attr}"
        else:
            module = _import_module(target)
            kind, full = "module", spec
    except PluginError:
        raise
    except Exception as exc:
        raise PluginError(
            f"planner spec {spec!r}: importing {target} failed: {type(exc).__name__}: {exc}"
        ) from exc
    if not hasattr(module, attr):
        names = _planner_classes(module)
        raise PluginError(
            f"planner spec {spec!r}: {target} has no {attr!r}{near(attr, names)}; its planner "
            f"classes: {', '.join(names) or 'none'}"
        )
    file = getattr(module, "__file__", None)
    dist, version = _distribution(module.__name__) if kind == "module" else (None, None)
    source = PlannerSource(kind, full, module.__name__, dist, version, file, _file_hash(file))
    return getattr(module, attr), source


def _planner_classes(module: Any) -> list[str]:
    """The names of the planner-like classes (with a ``plan``) a module defines."""
    return [
        n
        for n, v in vars(module).items()
        if inspect.isclass(v) and hasattr(v, "plan") and v.__module__ == module.__name__
    ]


def check_not_a_bare_file(text: str) -> None:
    """A planner given as ``file.py`` without ``:Name``: say how to name it, and which
    planner classes the file holds.

    Raises:
        PluginError: ``text`` names a Python file, not a planner.
    """
    if ":" in text or not text.endswith(".py"):
        return
    path = Path(text)
    if not path.is_file():
        raise PluginError(
            f"planner {text!r} looks like a file, which needs its class too (as "
            f"{text}:ClassName), and there is no file {path} (from {os.getcwd()})"
        )
    try:
        found = _planner_classes(_import_file(path))
    except Exception as exc:
        raise PluginError(
            f"planner {text!r} is a file, which needs its class too (as {text}:ClassName); "
            f"importing it failed: {type(exc).__name__}: {exc}"
        ) from exc
    example = f"{text}:{found[0] if found else 'ClassName'}"
    raise PluginError(
        f"planner {text!r} is a file: name the class too, as {example} (its planner classes: "
        f"{', '.join(found) or 'none'})"
    )


def _distribution(module: str) -> tuple[str | None, str | None]:
    """The installed package providing top-level module ``module`` and its version."""
    top = module.partition(".")[0]
    dists = metadata.packages_distributions().get(top, [])
    if not dists:
        return None, None
    try:
        return dists[0], metadata.version(dists[0])
    except metadata.PackageNotFoundError:
        return dists[0], None


def factory(obj: Any, label: str):
    """A registry factory ``(config=None) -> planner`` for a planner class or function ``obj``;
    building errors (an abstract method left out, a constructor that raises) become a
    PluginError naming the planner and, where its code raised, the file and line."""
    if not callable(obj):
        raise PluginError(f"planner {label}: {obj!r} is neither a planner class nor a function")

    def build(config: Any = None) -> Any:
        try:
            planner = obj() if config is None else obj(config)
        except MemoryError:
            raise
        except Exception as exc:  # the plugin's constructor: one line, at its own line
            from hsqbench.planner.failure import location, one_line

            where = location(exc, obj, own_only=True)
            what = f"{type(exc).__name__} at {where}: {exc}" if where else str(exc)
            raise PluginError(one_line(f"planner {label} cannot be built: {what}")) from exc
        if not callable(getattr(planner, "plan", None)):
            raise PluginError(
                f"planner {label}: {type(planner).__name__} has no plan(points, context) method "
                "(subclass hsqbench.planner.base.PlannerBase; see docs/your-own-planner.md)"
            )
        return planner

    return build


def planner_name_of(obj: Any, attr: str) -> str:
    """The name a spec's planner is registered under: ``obj.name`` if a string, else ``attr``."""
    name = getattr(obj, "name", None)
    return name if isinstance(name, str) and name else attr


def entry_points() -> dict[str, metadata.EntryPoint]:
    """Installed planners: entry point name -> entry point (nothing is imported)."""
    return {ep.name: ep for ep in metadata.entry_points(group=ENTRY_POINT_GROUP)}


def load_entry_point(name: str) -> Any:
    """Register the installed planner ``name`` and return its factory.

    Raises:
        PluginError: its package fails to import or lacks the object.
    """
    ep = entry_points()[name]
    try:
        obj = ep.load()
    except Exception as exc:
        dist = ep.dist.name if ep.dist else "its package"
        raise PluginError(
            f"installed planner {name!r} ({ep.value}, from {dist}) cannot be loaded: "
            f"{type(exc).__name__}: {exc}"
        ) from exc
    return factory(obj, repr(name))


def entry_point_source(name: str) -> PlannerSource:
    """Where installed planner ``name`` comes from (its module is imported to hash its file)."""
    ep = entry_points()[name]
    module = ep.value.partition(":")[0].strip()
    spec = importlib.util.find_spec(module)
    file = spec.origin if spec is not None else None
    dist = ep.dist.name if ep.dist else None
    version = ep.dist.version if ep.dist else None
    return PlannerSource("entry-point", ep.value, module, dist, version, file, _file_hash(file))
