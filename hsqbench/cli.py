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
from hsqbench.commands._options import show_required


class CommandError(RuntimeError):
    """A user-facing error: printed as ``hsqbench: error: ...`` with exit code 2."""


def user_errors() -> tuple[type[BaseException], ...]:
    """The exceptions that report a problem with the user's input, files or set-up (printed as
    one line, exit 2). ``ValueError`` is among them: every input check raises it, with a
    message naming the problem and the fix. Anything else (a ``RuntimeError``, ``KeyError``,
    ``TypeError``, ...) is a bug in hsqbench and keeps its traceback."""
    from hsqbench.assets.build import AssetError
    from hsqbench.assets.download import DownloadError
    from hsqbench.experiment.backend import TrialRunnerUnavailable
    from hsqbench.experiment.results import ResultsError
    from hsqbench.planner.learned.network import LearnedExtraMissing
    from hsqbench.settings import SettingError

    return (
        CommandError,
        ValueError,
        FileNotFoundError,
        AssetError,
        DownloadError,
        TrialRunnerUnavailable,
        ResultsError,
        LearnedExtraMissing,
        SettingError,
    )


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
        show_required(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from hsqbench.commands._options import check_outputs, check_required

    check_required(args)  # options that also have an old positional spelling
    try:
        check_outputs(args)  # every path the command writes, before it starts
        return int(args._run(args) or 0)
    except Exception as exc:
        if not isinstance(exc, user_errors()):
            raise  # an internal error: its traceback is what a bug report needs
        print(f"hsqbench {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    # `python -m hsqbench.cli` runs this file as __main__, but the commands raise
    # hsqbench.cli's CommandError: run that module's main, whose user_errors() knows it.
    from hsqbench.cli import main as cli_main

    sys.exit(cli_main())
