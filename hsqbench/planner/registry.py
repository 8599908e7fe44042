"""Planners by name, so that the harness, the CLI and configs can pick one with a string.

A factory takes an optional config (whatever that planner understands: a config object, a config
name or a YAML path) and returns a :class:`~hsqbench.planner.api.Planner`. Registering a new
planner is one call::

    from hsqbench.planner.registry import register_planner
    register_planner("antipodal", lambda config=None: AntipodalPlanner(config))

Factories import their planner lazily, so listing names costs nothing.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

from hsqbench.planner.hsq.additions import AdditionsConfig, ablation_planners

if TYPE_CHECKING:
    from hsqbench.planner.api import Planner

PlannerFactory = Callable[..., "Planner"]


def _hsq(config: Any = None) -> Planner:
    from hsqbench.planner.hsq.planner import HSQPlanner

    return HSQPlanner(config)


def _single_sq(config: Any = None) -> Planner:
    from hsqbench.planner.baselines.single_sq import SingleSQPlanner

    return SingleSQPlanner(config)


def _antipodal(config: Any = None) -> Planner:
    from hsqbench.planner.baselines.antipodal import AntipodalPlanner

    return AntipodalPlanner(config)


def _hsq_without(off: tuple[str, ...], name: str) -> PlannerFactory:
    """hsq with the additions ``off`` switched off (hsqbench.planner.hsq.additions)."""

    def factory(config: Any = None) -> Planner:
        from hsqbench.planner.hsq.planner import HSQPlanner

        return HSQPlanner(config, additions_off=off, name=name)

    return factory


def _oracle(config: Any = None) -> Planner:
    from hsqbench.planner.oracle import OraclePlanner

    return OraclePlanner(config)


def _contact_graspnet(config: Any = None, *, eliminate: bool = False) -> Planner:
    """Contact-GraspNet (optional extra ``learned``; without it the error says how to install)."""
    from hsqbench.planner.learned.contact_graspnet import ContactGraspNetPlanner

    name = "contact-graspnet-elim" if eliminate else "contact-graspnet"
    return ContactGraspNetPlanner(config, eliminate=eliminate, name=name)


def _volumetric(network: str) -> PlannerFactory:
    """VGN or GIGA (optional extra ``learned``, torch only; hsqbench.planner.learned.volumetric)."""

    def factory(config: Any = None) -> Planner:
        from hsqbench.planner.learned.volumetric import VolumetricPlanner

        return VolumetricPlanner(network, config)

    return factory


_FACTORIES: dict[str, PlannerFactory] = {
    "hsq": _hsq,
    "single-sq": _single_sq,
    "antipodal": _antipodal,
    "contact-graspnet": _contact_graspnet,
    "contact-graspnet-elim": lambda config=None: _contact_graspnet(config, eliminate=True),
    # The volumetric learned baselines with their published weights (configs/volumetric.yaml).
    "vgn": _volumetric("vgn"),
    "giga": _volumetric("giga"),
    # The paper's rules alone, and hsq with one addition off (the ablation planners).
    "hsq-paper": _hsq_without(tuple(AdditionsConfig.names()), "hsq-paper"),
    **{name: _hsq_without((addition,), name) for name, addition in ablation_planners().items()},
    # Privileged: reads the true meshes, not the cloud (hsqbench.planner.oracle).
    "oracle": _oracle,
}

#: Which entry of :class:`~hsqbench.planner.configs.PlannerConfigs` each planner reads.
_CONFIG_KEYS: dict[str, str] = {
    "single-sq": "baselines",
    "antipodal": "baselines",
    "contact-graspnet": "contact_graspnet",
    "contact-graspnet-elim": "contact_graspnet",
    "oracle": "oracle",
    "hsq": "hsq",
    "hsq-paper": "hsq",
    **{name: "hsq" for name in ablation_planners()},
}

#: Planners that read simulator truth: their rows are a ceiling, not a method to compare with.
PRIVILEGED = frozenset({"oracle"})


def unavailable(name: str) -> str | None:
    """Why planner ``name`` cannot run here (an optional extra is missing), or None.

    The benchmark leaves such planners out of a protocol's list with this message, so a protocol
    that names an optional planner still runs without its extra.
    """
    if name.startswith("contact-graspnet") and name in _FACTORIES:
        from hsqbench.planner.learned.network import INSTALL_HINT, available

        return None if available() else INSTALL_HINT
    if name in ("vgn", "giga") and name in _FACTORIES:
        from hsqbench.planner.learned import volumetric

        return None if volumetric.available() else volumetric.INSTALL_HINT
    return None


def runnable(names: Iterable[str]) -> list[str]:
    """``names`` less the planners that cannot run here, each left out with its reason on
    stderr (a protocol or sweep that lists an optional planner still runs without its extra)."""
    keep = []
    for name in names:
        why = unavailable(name)
        if why is None:
            keep.append(name)
        else:
            print(f"leaving out planner {name}: {why}", file=sys.stderr)
    return keep


def register_planner(
    name: str, factory: PlannerFactory, *, replace: bool = False, config_key: str | None = None
) -> None:
    """Make ``get_planner(name)`` call ``factory(config)``; ``config_key`` names the entry of
    the trial config's ``planners:`` it is built with (None: its own default).

    Raises:
        ValueError: ``name`` is empty, or already taken and ``replace`` is False.
    """
    if not name or not isinstance(name, str):
        raise ValueError(f"a planner name must be a non-empty string, got {name!r}")
    if name in _FACTORIES and not replace:
        raise ValueError(f"a planner named {name!r} is already registered (pass replace=True)")
    _FACTORIES[name] = factory
    if config_key is None:
        _CONFIG_KEYS.pop(name, None)
    else:
        _CONFIG_KEYS[name] = config_key


def planner_config_key(name: str) -> str | None:
    """The ``planners:`` entry planner ``name`` reads (None: none; it uses its default)."""
    return _CONFIG_KEYS.get(name)


def planner_names() -> list[str]:
    """Registered planner names, sorted."""
    return sorted(_FACTORIES)


def get_planner(name: str, config: Any = None) -> Planner:
    """A new planner ``name`` built with ``config`` (None: that planner's defaults).

    Raises:
        ValueError: unknown ``name``; the message lists the registered names.
        LearnedExtraMissing: (a RuntimeError) ``contact-graspnet*``, ``vgn`` or ``giga``
            without the ``learned`` extra; the message says how to install it.
    """
    try:
        factory = _FACTORIES[name]
    except KeyError:
        raise ValueError(
            f"unknown planner {name!r}; choose one of: {', '.join(planner_names())}"
        ) from None
    return factory(config)
