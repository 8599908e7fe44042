"""``hsqbench planners``: every planner, one line each: built-in, installed, plugged in, or
needing an optional extra (with the command that installs it)."""

from __future__ import annotations

import argparse

HELP = "list every planner: built-in, installed plugins, and those needing an optional extra"

_EPILOG = """\
Your own planner plugs in two ways (docs/your-own-planner.md):
  an installed package's entry point in the group "hsqbench.planners" (listed here by name), or
  a spec where a planner name goes: --planner module:Name or --planner path/to/file.py:Name.
Name specs here to check that they load and build, e.g. `hsqbench planners examples/topdown.py:TopDown`.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument(
        "specs",
        nargs="*",
        metavar="SPEC",
        help="planner specs (module:Name, path/to/file.py:Name) to load, build and list too",
    )


def _status(name: str) -> tuple[str, str]:
    """(kind, one line) of planner ``name``."""
    from hsqbench.planner import plugins
    from hsqbench.planner.hsq.additions import ablation_planners
    from hsqbench.planner.registry import (
        DESCRIPTIONS,
        PRIVILEGED,
        is_builtin,
        source_of,
        unavailable,
    )

    if is_builtin(name):
        if (why := unavailable(name)) is not None:
            return "needs extra", f"{DESCRIPTIONS[name]}; not installed: {why}"
        addition = ablation_planners().get(name)
        if addition is not None:
            text = f"ablation: hsq with '{addition}' off (additions: in configs/planner.yaml)"
        else:
            text = DESCRIPTIONS[name]
        return ("built-in, privileged" if name in PRIVILEGED else "built-in"), text
    source = source_of(name)
    if source is None:
        return "registered", "registered in this process (register_planner)"
    where = source.spec
    if source.distribution:
        where += f" (package {source.distribution} {source.version or ''})".rstrip()
    if source.kind == "entry-point":
        try:
            plugins.load_entry_point(name)
        except plugins.PluginError as exc:
            return "installed, broken", str(exc)
        return "installed", where
    return "plugged in", where


def run(args: argparse.Namespace) -> int:
    from hsqbench.planner.registry import get_planner, is_builtin, planner_names, resolve_planners

    for name in resolve_planners(args.specs):
        get_planner(name)  # a spec must build, or the error says why (exit 2)
    from hsqbench.planner.hsq.additions import ablation_planners

    ablations = ablation_planners()
    # hsqbench's planners first, their ablations next, plugins last.
    names = sorted(planner_names(), key=lambda n: (not is_builtin(n), n in ablations, n))
    rows = [(n, *_status(n)) for n in names]
    width = [max(len(r[i]) for r in rows) for i in range(2)]
    for name, kind, text in rows:
        print(f"{name:{width[0]}}  {kind:{width[1]}}  {text}")
    n_plugins = sum(not k.startswith(("built-in", "needs")) for _, k, _ in rows)
    print(
        f"{len(rows)} planners ({n_plugins} from plugins); add yours with --planner "
        "module:Name or path/to/file.py:Name, or an entry point in 'hsqbench.planners'"
    )
    return 0
