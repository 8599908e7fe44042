"""Config overrides: dotted paths into a config's data, applied before its dataclass is built.

A sweep point (and any protocol with ``overrides:``) changes a few values of the trial's config
tree without a new YAML file per value::

    perception.tof.sigma_quad_per_m: 0.002      # a field of a nested config
    robot.pads.friction.0: 0.5                  # an element of a list (0 = sliding friction)
    scene.depth_cameras.names: [cam_left]       # a whole value (here: one camera)

The trial's config tree is the trial config (``configs/trial.yaml``) with every config it names
by file read in (:func:`hsqbench.config.load_tree`, the one place a tree is loaded and these
overrides applied); a path's first key is one of its fields (``perception``,
``execution.lift_height_m``, ``planners.hsq.grasp.max_tilt_deg``).

:func:`apply_overrides` is the one place overrides are applied: every key is checked against the
dataclass fields (not only the keys the YAML happens to hold), so a typo is an error naming the
path and the valid keys, and the values then pass the dataclass's own type checks.
"""

from __future__ import annotations

import copy
import dataclasses
import json
import types
import typing
from collections.abc import Mapping
from typing import Any

from hsqbench.errors import ConfigError


def _plain(value: Any) -> Any:
    """A default value as config data (dataclasses to mappings, tuples to lists)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        value = dataclasses.asdict(value)
    return json.loads(json.dumps(value, default=list))


def _default(cls: type, name: str) -> Any:
    f = next(f for f in dataclasses.fields(cls) if f.name == name)
    if f.default is not dataclasses.MISSING:
        return _plain(f.default)
    if f.default_factory is not dataclasses.MISSING:
        return _plain(f.default_factory())
    return None


def _dataclass_of(tp: Any) -> type | None:
    """The dataclass in a field type (``X`` or ``X | None``), else None."""
    if dataclasses.is_dataclass(tp):
        return tp
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        found = [a for a in typing.get_args(tp) if dataclasses.is_dataclass(a)]
        return found[0] if len(found) == 1 else None
    return None


def _item_type(tp: Any, index: int) -> Any:
    """The type of element ``index`` of a ``tuple[...]`` or ``list[...]`` field type."""
    args = [a for a in typing.get_args(tp) if a is not Ellipsis]
    if len(args) == 1:
        return args[0]
    return args[index] if index < len(args) else Any


def _set(data: dict[str, Any], cls: type, keys: list[str], value: Any, path: str) -> None:
    """Set ``value`` at ``keys`` below ``data`` (the data of dataclass ``cls``)."""
    node: Any = data
    tp: Any = cls
    for depth, key in enumerate(keys):
        last = depth == len(keys) - 1
        here = ".".join(keys[:depth]) or "the top level"
        klass = _dataclass_of(tp)
        if klass is not None:
            fields = {f.name: f for f in dataclasses.fields(klass) if f.init}
            if key not in fields:
                raise ConfigError(
                    f"override {path!r}: {key!r} is not a key of {here} ({klass.__name__}); "
                    f"valid keys: {sorted(fields)}"
                )
            if last:
                node[key] = copy.deepcopy(value)
                return
            if not isinstance(node.get(key), dict | list):
                node[key] = _default(klass, key)
            tp = typing.get_type_hints(klass)[key]
            node = node[key]
        elif isinstance(node, list):
            if not (key.isdigit() and int(key) < len(node)):
                raise ConfigError(
                    f"override {path!r}: {key!r} is not an index of {here}, a list of "
                    f"{len(node)} value(s) (valid: 0 to {len(node) - 1})"
                )
            if last:
                node[int(key)] = copy.deepcopy(value)
                return
            tp = _item_type(tp, int(key))
            node = node[int(key)]
        elif isinstance(node, dict):
            if last:
                node[key] = copy.deepcopy(value)
                return
            node = node.setdefault(key, {})
            tp = Any
        else:
            raise ConfigError(
                f"override {path!r}: {here} holds {node!r}, which has no keys; valid paths "
                f"end at {here}"
            )


def apply_overrides(
    data: Mapping[str, Any], overrides: Mapping[str, Any], cls: type, where: str = ""
) -> dict[str, Any]:
    """``data`` (the mapping of a config file of dataclass ``cls``) with ``overrides`` applied.

    Args:
        overrides: dotted path -> value; a path's keys are the dataclass's fields, integer
            indices into lists (``friction.0``) and, in plain mappings, any key. Applied in
            order, so a later path may refine an earlier whole value.
        where: prefix of the paths in error messages (e.g. ``"perception"``).

    Raises:
        ConfigError: an empty path, a key the dataclass does not have (naming the valid ones),
            or an index outside a list.
    """
    out = copy.deepcopy(dict(data))
    for path, value in overrides.items():
        full = f"{where}.{path}" if where else path
        keys = path.split(".") if isinstance(path, str) else []
        if not keys or not all(keys):
            raise ConfigError(f"override {full!r}: a path is keys joined by '.', e.g. a.b.0")
        _set(out, cls, keys, value, full)
    return out


def parse_assignments(items: list[str]) -> dict[str, Any]:
    """``--set KEY=VALUE`` items of a command line as overrides, each value read as YAML
    (``ik.restarts=4`` -> ``{"ik.restarts": 4}``).

    Raises:
        ConfigError: an item without ``=`` or with an empty key, naming the form to write.
    """
    import yaml

    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(
                f"--set {item!r}: write KEY=VALUE, e.g. execution.release_height_m=0.01"
            )
        out[key.strip()] = yaml.safe_load(value)
    return out
