"""A robustness sweep: protocols, planners and seeds, and parameters each stepped over points.

``configs/protocols/sweeps/<name>.yaml`` (or ``hsqbench sweep --param PATH --values ...``) loaded into
frozen dataclasses. A point is a set of config overrides (:mod:`hsqbench.overrides`) with a label
and a position on the plot's axis; one parameter may move several values together (a
calibration error's translation and rotation). Every point of every protocol is an ordinary run
(:mod:`hsqbench.experiment.sweep`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hsqbench.config import load_config
from hsqbench.errors import ConfigError
from hsqbench.experiment.config import EXPERIMENTS


@dataclass(frozen=True)
class SweepPoint:
    """One setting of a parameter.

    Attributes:
        label: how the plot and the CSV name it (``"2x"``, ``"left only"``).
        overrides: dotted config path -> value; empty: the protocol's own settings.
        x: position on the axis; None on every point of a parameter: evenly spaced categories.
    """

    label: str
    overrides: dict[str, Any] = field(default_factory=dict)
    x: float | None = None

    def __post_init__(self) -> None:
        if not self.label.strip():
            raise ConfigError("a sweep point needs a non-empty label")


def _label(value: Any) -> str:
    """A value as a point label: lists joined by '+' (``cam_left+cam_right``)."""
    if isinstance(value, list | tuple):
        return "+".join(_label(v) for v in value)
    return value if isinstance(value, str) else str(value)


@dataclass(frozen=True)
class SweepParameter:
    """A parameter and its points: either ``path`` with ``values`` (each value one point, the
    value its label and, when a number, its x) or ``points`` spelled out.

    Attributes:
        name: the parameter's name in the CSV and its plot's file name (letters, digits, _ -).
        axis: the x-axis label (default: the path, or the name).
    """

    name: str
    axis: str = ""
    path: str = ""
    values: tuple[Any, ...] = ()
    points: tuple[SweepPoint, ...] = ()

    def __post_init__(self) -> None:
        if not re.fullmatch(r"[A-Za-z0-9_-]+", self.name):
            raise ConfigError(f"sweep parameter name {self.name!r}: use letters, digits, _ or -")
        if bool(self.path) == bool(self.points):
            raise ConfigError(
                f"sweep parameter {self.name!r}: give either path with values, or points"
            )
        if self.path:
            if not self.values:
                raise ConfigError(f"sweep parameter {self.name!r}: path {self.path!r} needs values")
            numeric = all(
                isinstance(v, int | float) and not isinstance(v, bool) for v in self.values
            )
            points = tuple(
                SweepPoint(_label(v), {self.path: v}, float(v) if numeric else None)
                for v in self.values
            )
            object.__setattr__(self, "points", points)
        labels = [p.label for p in self.points]
        if len(set(labels)) != len(labels):
            raise ConfigError(f"sweep parameter {self.name!r}: point labels repeat: {labels}")
        if len({p.x is None for p in self.points}) > 1:
            raise ConfigError(
                f"sweep parameter {self.name!r}: give x on every point or on none (categories)"
            )
        if not self.axis:
            object.__setattr__(self, "axis", self.path or self.name)

    @property
    def categorical(self) -> bool:
        return self.points[0].x is None


@dataclass(frozen=True)
class SweepProtocol:
    """A protocol the parameters are stepped on, and its size per point.

    Attributes:
        config: protocol config (``paper``, ``ycb`` or a path); its objects and trial config.
        attempts_per_object: isolated attempts per object and base seed at every point
            (None: the protocol's own).
        rounds: packed (and pile) rounds per base seed at every point (None: the protocol's own).
        seeds: base seeds on this protocol (None: the sweep's), so a small protocol can spread
            its attempts over three seeds while a large one runs one.
    """

    config: str
    attempts_per_object: int | None = None
    rounds: int | None = None
    seeds: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        for name in ("attempts_per_object", "rounds"):
            value = getattr(self, name)
            if value is not None and value < 1:
                raise ConfigError(f"sweep protocol {self.config!r}: {name} must be >= 1")
        if self.seeds is not None and (not self.seeds or len(set(self.seeds)) != len(self.seeds)):
            raise ConfigError(
                f"sweep protocol {self.config!r}: seeds {list(self.seeds)} must be distinct and "
                "at least one (or leave seeds out for the sweep's)"
            )

    @property
    def name(self) -> str:
        return Path(self.config).stem if self.config.endswith((".yaml", ".yml")) else self.config


@dataclass(frozen=True)
class SweepConfig:
    """One sweep (``configs/protocols/sweeps/*.yaml``).

    Attributes:
        protocols: where the parameters are stepped (each point runs on every protocol).
        experiments: which of the protocols' experiments run (``isolated``, ``packed``, ``pile``).
        planners: the planners (optional ones whose extra is missing are left out with a note).
        seeds: base seeds; every point runs the same trials (same poses), so points differ only
            by their settings. More seeds repeat the protocol on fresh poses.
        parameters: the parameters, each with its points.
    """

    protocols: tuple[SweepProtocol, ...]
    parameters: tuple[SweepParameter, ...]
    experiments: tuple[str, ...] = ("isolated",)
    planners: tuple[str, ...] = ("hsq", "single-sq", "antipodal")
    seeds: tuple[int, ...] = (0,)

    def __post_init__(self) -> None:
        if not self.protocols or not self.parameters:
            raise ConfigError("a sweep needs at least one protocol and one parameter")
        bad = [e for e in self.experiments if e not in EXPERIMENTS]
        if bad or not self.experiments:
            raise ConfigError(
                f"sweep experiments {list(self.experiments)}: choose from {EXPERIMENTS}"
            )
        names = [p.name for p in self.parameters]
        if len(set(names)) != len(names):
            raise ConfigError(f"sweep parameter names repeat: {names}")
        protocols = [p.name for p in self.protocols]
        if len(set(protocols)) != len(protocols):
            raise ConfigError(f"sweep protocols repeat: {protocols}")


def load_sweep_config(name_or_path: str | Path) -> SweepConfig:
    """``configs/protocols/sweeps/<name>.yaml`` (``depth_noise``), a name under ``configs/`` or a
    path."""
    path = Path(name_or_path)
    if not path.suffix and "/" not in str(name_or_path):
        from hsqbench.settings import SWEEP_DIR

        path = SWEEP_DIR / f"{name_or_path}.yaml"
        if not path.exists():
            known = sorted(p.stem for p in SWEEP_DIR.glob("*.yaml"))
            raise ConfigError(
                f"no sweep {str(name_or_path)!r} in configs/protocols/sweeps/; known: {known}"
            )
        name_or_path = path
    return load_config(SweepConfig, name_or_path)
