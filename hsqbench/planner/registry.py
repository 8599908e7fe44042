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
    from hsqbench.planner.plugins import PlannerSource

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

#: One line on each built-in planner (``hsqbench planners``; the ablations are described from
#: their addition's sentence).
DESCRIPTIONS: dict[str, str] = {
    "hsq": "the paper's method (hidden superquadrics) with our additions (configs/planner.yaml)",
    "hsq-paper": "the paper's rules alone: hsq with every addition off",
    "single-sq": "baseline: one superquadric per object, the approach the paper improves on",
    "antipodal": "baseline: antipodal pairs of surface normals (GPD-style candidate sampler)",
    "contact-graspnet": "learned baseline: Contact-GraspNet (Sundermeyer et al., ICRA 2021)",
    "contact-graspnet-elim": "Contact-GraspNet's grasps through the harness's elimination rules",
    "oracle": "privileged ceiling: plans on the true meshes, not the cloud",
    "vgn": "learned baseline: VGN (Breyer et al., CoRL 2020) on a TSDF of the depth images",
    "giga": "learned baseline: GIGA (Jiang et al., RSS 2021) on a TSDF of the depth images",
}

#: The planners of hsqbench itself (the others come from plugins: :mod:`.plugins`).
_BUILTIN = frozenset(_FACTORIES)


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
    """Planner names, sorted: built-in, registered, and installed (entry points of
    ``hsqbench.planners``, not imported until used)."""
    from hsqbench.planner.plugins import entry_points

    return sorted(set(_FACTORIES) | set(entry_points()))


def is_builtin(name: str) -> bool:
    """Whether ``name`` is one of hsqbench's own planners."""
    return name in _BUILTIN


def get_planner(name: str, config: Any = None) -> Planner:
    """A new planner ``name`` built with ``config`` (None: that planner's defaults).

    ``name`` may be a spec (``module:Name``, ``path/to/file.py:Name``): see
    :func:`resolve_planner`.

    Raises:
        ValueError: unknown ``name``; the message lists the registered names.
        LearnedExtraMissing: (a RuntimeError) ``contact-graspnet*``, ``vgn`` or ``giga``
            without the ``learned`` extra; the message says how to install it.
    """
    return _factory(resolve_planner(name))(config)


def _factory(name: str) -> PlannerFactory:
    """The factory of known planner ``name``, loading an installed one on first use."""
    if name not in _FACTORIES:
        from hsqbench.planner.plugins import load_entry_point

        _FACTORIES[name] = load_entry_point(name)
    return _FACTORIES[name]


def resolve_planner(name_or_spec: str) -> str:
    """The name of a planner given by name or by spec (``module:Name``, ``file.py:Name``,
    registered here on first use: :mod:`hsqbench.planner.plugins`).

    Raises:
        ValueError: an unknown name (with the closest known one, and every choice), or a spec
            that cannot be loaded (:class:`~hsqbench.planner.plugins.PluginError`).
    """
    from hsqbench.names import near
    from hsqbench.planner.plugins import check_not_a_bare_file, is_spec

    if is_spec(name_or_spec):
        return register_spec(name_or_spec)
    check_not_a_bare_file(name_or_spec)
    names = planner_names()
    if name_or_spec not in names:
        raise ValueError(
            f"unknown planner {name_or_spec!r}{near(name_or_spec, names)}; choose one of: "
            f"{', '.join(names)}, or give your own as module:Name or path/to/file.py:Name"
        )
    return name_or_spec


def resolve_planners(items: Iterable[str]) -> list[str]:
    """:func:`resolve_planner` of each item, duplicates dropped."""
    return list(dict.fromkeys(resolve_planner(p) for p in items))


# Planners registered here from specs (module:Name, file.py:Name): name -> where from.
_SPECS: dict[str, PlannerSource] = {}


def register_spec(spec: str) -> str:
    """Register the planner of ``spec`` (once per process) and return its name.

    Raises:
        PluginError: the spec cannot be loaded, or its name is taken by another planner.
    """
    from hsqbench.planner.plugins import (
        PluginError,
        entry_points,
        factory,
        load_spec,
        planner_name_of,
    )

    obj, source = load_spec(spec)
    name = planner_name_of(obj, spec.rpartition(":")[2])
    if name in _SPECS:
        if _SPECS[name].spec != source.spec:
            raise PluginError(
                f"planner name {name!r} of {spec!r} is already taken by {_SPECS[name].spec}; "
                "give one of them another name attribute"
            )
        return name
    if is_builtin(name) or name in entry_points():
        raise PluginError(
            f"planner name {name!r} of {spec!r} is taken by a built-in or installed planner; "
            "set another `name` on the class"
        )
    if bad := [c for c in "/,; " if c in name]:
        raise PluginError(f"planner name {name!r} of {spec!r} must not contain {bad}")
    register_planner(name, factory(obj, repr(spec)))
    _SPECS[name] = source
    return name


def specs_of() -> tuple[tuple[str, str], ...]:
    """``(name, spec)`` of the planners registered from specs in this process, for worker
    processes to register them again (:func:`register_specs`)."""
    return tuple((n, s.spec) for n, s in _SPECS.items())


def register_specs(pairs: tuple[tuple[str, str], ...]) -> None:
    """Register ``(name, spec)`` pairs from :func:`specs_of` (in a worker).

    Raises:
        PluginError: a spec now yields another name (its file changed under the run).
    """
    from hsqbench.planner.plugins import PluginError

    for name, spec in pairs:
        if name not in _SPECS and (got := register_spec(spec)) != name:
            raise PluginError(f"planner spec {spec!r} now names {got!r}, not {name!r}")


def source_of(name: str) -> PlannerSource | None:
    """Where planner ``name``'s code comes from; None for a planner of hsqbench itself."""
    from hsqbench.planner.plugins import entry_point_source, entry_points

    if name in _SPECS:
        return _SPECS[name]
    if not is_builtin(name) and name in entry_points():
        return entry_point_source(name)
    return None


def planner_sources(names: Iterable[str]) -> dict[str, dict[str, Any]]:
    """Where each plugin planner among ``names`` comes from (``{}`` when all are hsqbench's):
    part of a run's identity, so a run's results name the code behind each planner."""
    return {n: s.to_dict() for n in names if (s := source_of(n)) is not None}
