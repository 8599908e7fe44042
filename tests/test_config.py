"""Typed config loading: overrides, nesting and errors that name the key."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from hsqbench.config import ConfigError, config_hash, from_dict, load_config


@dataclass(frozen=True)
class Inner:
    spacing_m: float = 0.005
    names: tuple[str, ...] = ("a",)


@dataclass(frozen=True)
class Outer:
    iterations: int = 20
    enabled: bool = True
    inner: Inner = field(default_factory=Inner)


def test_defaults_and_overrides() -> None:
    cfg = from_dict(Outer, {"iterations": 5, "inner": {"spacing_m": 1}})
    assert cfg.iterations == 5
    assert cfg.inner.spacing_m == 1.0 and isinstance(cfg.inner.spacing_m, float)
    assert cfg.inner.names == ("a",)
    assert load_config(Outer) == Outer()


@pytest.mark.parametrize(
    ("data", "needle"),
    [
        ({"iteration": 5}, "iteration"),
        ({"iterations": 2.5}, "iterations"),
        ({"enabled": "yes"}, "enabled"),
        ({"inner": {"spacing": 1.0}}, "inner"),
    ],
)
def test_errors_name_the_key(data: dict, needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        from_dict(Outer, data)


def test_hash_changes_with_values() -> None:
    assert config_hash(Outer()) == config_hash(Outer())
    assert config_hash(Outer()) != config_hash(Outer(iterations=21))


def test_unknown_config_name_lists_choices() -> None:
    with pytest.raises(ConfigError, match="not one of"):
        load_config(Outer, "no-such-config")
