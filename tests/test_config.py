"""Typed config loading: overrides, nesting and errors that name the key."""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

from hsqbench.config import config_hash, from_dict, load_config
from hsqbench.errors import ConfigError


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
    with pytest.raises(
        ConfigError, match=r"protocols: \[.*'paper'.*component configs: \[.*'trial'"
    ):
        load_config(Outer, "no-such-config")
    with pytest.raises(ConfigError, match=r"no config file 'nowhere/x\.yaml'"):
        load_config(Outer, "nowhere/x.yaml")


def test_a_bare_name_is_a_component_config_or_a_protocol() -> None:
    from hsqbench.config import resolve_config_path
    from hsqbench.settings import CONFIG_DIR, PROTOCOL_DIR

    assert resolve_config_path("trial") == CONFIG_DIR / "trial.yaml"
    assert resolve_config_path("paper") == PROTOCOL_DIR / "paper.yaml"
    assert resolve_config_path("protocols/sweeps/cameras") == PROTOCOL_DIR / "sweeps/cameras.yaml"
    # A protocol named like a component config would shadow nothing silently: none is.
    components = {p.stem for p in CONFIG_DIR.glob("*.yaml")}
    assert components and not components & {p.stem for p in PROTOCOL_DIR.glob("*.yaml")}


def test_a_relative_extends_is_read_beside_the_variant_from_any_folder(tmp_path, monkeypatch):
    """A variant in the user's folder extends a file next to it, whatever the working folder."""
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "base.yaml").write_text("iterations: 7\n")
    (tmp_path / "mine" / "variant.yaml").write_text("extends: base.yaml\nenabled: false\n")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    assert load_config(Outer, "../mine/variant.yaml") == Outer(iterations=7, enabled=False)
    (tmp_path / "mine" / "variant.yaml").write_text("extends: missing.yaml\n")
    with pytest.raises(ConfigError, match=r"missing\.yaml"):
        load_config(Outer, tmp_path / "mine" / "variant.yaml")


def test_extends_overrides_only_the_keys_it_names(tmp_path) -> None:
    (tmp_path / "base.yaml").write_text("iterations: 5\ninner:\n  spacing_m: 0.01\n  names: [x]\n")
    (tmp_path / "variant.yaml").write_text(
        f"extends: {tmp_path / 'base.yaml'}\ninner:\n  spacing_m: 0.02\n"
    )
    cfg = load_config(Outer, tmp_path / "variant.yaml")
    assert cfg.iterations == 5  # from the base
    assert cfg.inner.spacing_m == 0.02  # overridden
    assert cfg.inner.names == ("x",)  # the rest of the nested mapping kept


def test_extends_loop_and_bad_value_are_errors(tmp_path) -> None:
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    a.write_text(f"extends: {b}\n")
    b.write_text(f"extends: {a}\n")
    with pytest.raises(ConfigError, match="chain loops"):
        load_config(Outer, a)
    a.write_text("extends: [x, y]\n")
    with pytest.raises(ConfigError, match="must name one config"):
        load_config(Outer, a)


def test_load_tree_expands_named_configs_and_applies_overrides(tmp_path) -> None:
    """A nested config given by name is that file's mapping; overrides reach into it, also
    into keys the file leaves at their defaults, before the dataclasses are built."""
    from hsqbench.config import load_tree

    (tmp_path / "inner.yaml").write_text("spacing_m: 0.002\n")
    (tmp_path / "outer.yaml").write_text(f"inner: {tmp_path / 'inner.yaml'}\niterations: 3\n")
    tree = load_tree(Outer, tmp_path / "outer.yaml")
    assert tree == Outer(iterations=3, inner=Inner(spacing_m=0.002))
    moved = load_tree(Outer, tmp_path / "outer.yaml", {"inner.names": ["b", "c"]})
    assert moved.inner == Inner(spacing_m=0.002, names=("b", "c"))
    with pytest.raises(ConfigError, match=r"'nothing' is not a key of inner.*valid keys"):
        load_tree(Outer, tmp_path / "outer.yaml", {"inner.nothing": 1})
    with pytest.raises(ConfigError, match="has no keys"):
        load_tree(Outer, tmp_path / "outer.yaml", {"iterations.x": 1})
