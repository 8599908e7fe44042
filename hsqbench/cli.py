"""The ``hsqbench`` command line.

Each subcommand lives in ``hsqbench/commands/<name>.py`` and defines ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Modules are discovered, so adding a command
means adding a file. Heavy imports belong inside ``run`` to keep ``hsqbench --help`` fast.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from hsqbench import __version__, commands


class CommandError(RuntimeError):
    """A user-facing error: printed as ``hsqbench: error: ...`` with exit code 2."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hsqbench",
        description="Learning-free grasping with hidden superquadrics, benchmarked in MuJoCo.",
    )
    parser.add_argument("--version", action="version", version=f"hsqbench {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"hsqbench.commands.{info.name}")
        cmd = sub.add_parser(info.name, help=module.HELP, description=module.HELP)
        module.add_arguments(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args._run(args) or 0)
    except (CommandError, ValueError, FileNotFoundError, RuntimeError) as exc:
        print(f"hsqbench {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
