"""Typed configuration: YAML files in ``configs/`` loaded into frozen dataclasses.

Every config class is a (possibly nested) dataclass with defaults; a YAML file overrides any
subset of fields. Unknown keys and values of the wrong type are errors that name the key, so a
typo in a config never passes silently.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import types
import typing
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import yaml

from hsqbench.errors import ConfigError
from hsqbench.overrides import apply_overrides
from hsqbench.settings import CONFIG_DIR, PROTOCOL_DIR

T = TypeVar("T")


#: Where a bare config name is looked up: the component configs (``planner``, ``trial``), then
#: the protocols (``paper``, ``quick``). No name is in both (tests/test_config_defaults.py).
SEARCH_DIRS = (CONFIG_DIR, PROTOCOL_DIR)


def resolve_config_path(name_or_path: str | Path) -> Path:
    """``"planner"`` -> ``configs/planner.yaml``, ``"paper"`` -> ``configs/protocols/paper.yaml``;
    an existing YAML path is returned as is."""
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml"):
        if path.exists():
            return path
        raise ConfigError(f"no config file {str(path)!r} (looked from {Path.cwd()})")
    for folder in SEARCH_DIRS:
        candidate = folder / f"{name_or_path}.yaml"
        if candidate.exists():
            return candidate
    protocols = sorted(p.stem for p in PROTOCOL_DIR.glob("*.yaml"))
    components = sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))
    raise ConfigError(
        f"no config {str(name_or_path)!r}: not a YAML file; protocols: {protocols}, "
        f"component configs: {components}"
    )


def _coerce(value: Any, tp: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if dataclasses.is_dataclass(tp):
        if isinstance(value, str):  # a config named where its mapping may stand
            value = expand_names(tp, load_config_data(value), f"{where} ({value})")
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping, got {type(value).__name__}")
        return from_dict(tp, value, where)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, where)
            except ConfigError as exc:
                errors.append(str(exc))
        raise ConfigError(errors[0] if errors else f"{where}: invalid value {value!r}")
    if origin is typing.Literal:
        if value not in args:
            raise ConfigError(f"{where}: {value!r} is not one of {list(args)}")
        return value
    if origin in (tuple, list):
        if not isinstance(value, list | tuple):
            raise ConfigError(f"{where}: expected a list, got {value!r}")
        if origin is tuple and args and args[-1] is not Ellipsis:
            if len(value) != len(args):
                raise ConfigError(f"{where}: expected {len(args)} values, got {len(value)}")
            return tuple(
                _coerce(v, a, f"{where}[{i}]")
                for i, (v, a) in enumerate(zip(value, args, strict=True))
            )
        item = args[0] if args else Any
        seq = [_coerce(v, item, f"{where}[{i}]") for i, v in enumerate(value)]
        return tuple(seq) if origin is tuple else seq
    if origin is dict:
        if not isinstance(value, dict):
            raise ConfigError(f"{where}: expected a mapping, got {value!r}")
        return dict(value)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(f"{where}: expected a number, got {value!r}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(f"{where}: expected an integer, got {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"{where}: expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(f"{where}: expected a string, got {value!r}")
        return value
    return value


def from_dict(cls: type[T], data: dict[str, Any], where: str = "") -> T:
    """Build dataclass ``cls`` from a mapping, recursing into nested dataclasses."""
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    unknown = set(data) - set(fields)
    if unknown:
        raise ConfigError(
            f"{where or cls.__name__}: unknown key(s) {sorted(unknown)}; known: {sorted(fields)}"
        )
    kwargs = {
        name: _coerce(value, hints[name], f"{where}.{name}" if where else name)
        for name, value in data.items()
    }
    try:
        return cls(**kwargs)
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{where or cls.__name__}: {exc}") from exc


#: Top-level key of a config file that names the file it overrides (see :func:`load_config`).
EXTENDS = "extends"


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over`` on top of ``base``: mappings merge key by key, anything else replaces."""
    out = dict(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def load_config_data(name_or_path: str | Path, _chain: tuple[Path, ...] = ()) -> dict[str, Any]:
    """The mapping of a config file, with its ``extends:`` chain applied (the named base file
    first, then this file's keys on top), so a variant states only what it changes."""
    path = resolve_config_path(name_or_path)
    if path.resolve() in _chain:
        names = " -> ".join(p.name for p in (*_chain, path.resolve()))
        raise ConfigError(f"{path}: '{EXTENDS}' chain loops: {names}")
    try:
        data = yaml.safe_load(path.read_text()) or {}
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: the top level must be a mapping")
    base = data.pop(EXTENDS, None)
    if base is None:
        return data
    if not isinstance(base, str):
        raise ConfigError(f"{path}: '{EXTENDS}' must name one config, got {base!r}")
    return _merge(load_config_data(_beside(base, path), (*_chain, path.resolve())), data)


def _beside(base: str, path: Path) -> str | Path:
    """The file ``extends:`` names: a relative YAML path is read next to the file that names it
    (a variant works from any folder); a bare name is a config of ``configs/``."""
    ref = Path(base)
    if ref.suffix in (".yaml", ".yml") and not ref.is_absolute():
        return path.parent / ref
    return base


def _config_class(tp: Any) -> Any:
    """The config dataclass a field holds (``X`` or ``X | None``), or None."""
    if dataclasses.is_dataclass(tp):
        return tp
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        found = [a for a in typing.get_args(tp) if dataclasses.is_dataclass(a)]
        return found[0] if len(found) == 1 else None
    return None


def expand_names(cls: Any, data: dict[str, Any], where: str = "") -> dict[str, Any]:
    """``data`` for config class ``cls`` with every config *named* where a nested config stands
    (``scene: scene`` for a ``SceneConfig`` field) replaced by that file's mapping (its
    ``extends:`` applied), recursively: the whole tree as one mapping, before any dataclass is
    built, so that overrides (:func:`hsqbench.overrides.apply_overrides`) can reach into any file of it."""
    hints = typing.get_type_hints(cls)
    out = dict(data)
    for name, value in data.items():
        sub = _config_class(hints.get(name))
        if sub is None:
            continue
        here = f"{where}.{name}" if where else name
        if isinstance(value, str | Path):
            out[name] = expand_names(sub, load_config_data(value), f"{here} ({value})")
        elif isinstance(value, dict):
            out[name] = expand_names(sub, value, here)
    return out


def load_tree(cls: type[T], name_or_path: str | Path, overrides: dict[str, Any] | None = None) -> T:
    """THE place where a config tree is loaded: the file (``extends:`` applied), every config
    it names expanded into it (:func:`expand_names`), ``overrides`` applied to that mapping
    (:func:`hsqbench.overrides.apply_overrides`: every path checked against the dataclasses),
    then the dataclasses built, each validating its own values."""
    path = resolve_config_path(name_or_path)
    data = expand_names(cls, load_config_data(path), path.name)
    if overrides:
        data = apply_overrides(data, overrides, cls)
    return from_dict(cls, data, where=path.name)


def load_config(cls: type[T], name_or_path: str | Path | None = None) -> T:
    """Load ``cls`` from a YAML file (a name in ``configs/`` or a path); defaults when ``None``.

    A file may start with ``extends: <name or path>``: it is then that config with this file's
    keys on top (nested mappings merged), e.g. ``configs/scene_resting.yaml``.
    """
    if name_or_path is None:
        return cls()
    return load_tree(cls, name_or_path)


def to_dict(config: Any) -> dict[str, Any]:
    """A plain mapping of a config dataclass (tuples become lists), for JSON and YAML."""
    return json.loads(json.dumps(dataclasses.asdict(config), default=list))


def config_hash(config: Any) -> str:
    """A short, stable hash of a config's values, stored with every result row."""
    blob = json.dumps(to_dict(config), sort_keys=True).encode()
    return hashlib.sha256(blob).hexdigest()[:12]


def load_cached(loader: Callable[[str], T], name_or_path: str | Path) -> T:
    """``loader`` of the config ``name_or_path`` (a name in ``configs/`` or a YAML path), parsed
    once per modification time of the file (planning many clouds re-reads nothing)."""
    path = resolve_config_path(name_or_path)
    return _load_cached(loader, str(path), path.stat().st_mtime_ns)


@functools.lru_cache(maxsize=32)
def _load_cached(loader: Any, path: str, mtime_ns: int) -> Any:
    return loader(path)
