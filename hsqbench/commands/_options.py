"""The options several commands share, defined once so that each means the same everywhere.

docs/cli.md is the vocabulary (idea -> option -> commands -> old spellings), and
tests/test_cli_vocabulary.py holds every command's parser to it. In short:

- ``--planner PLANNER`` where a command uses one planner, ``--planners PLANNER...`` where it
  takes several (names or plugin specs ``module:Name``, ``file.py:Name``);
- ``--run RUN``: the run folder a command writes or reads (a name under runs/ or a path);
- ``--protocol NAME`` (one) / ``--protocols NAME...`` (several): benchmark protocols;
- ``--seed N`` (one) / ``--seeds N...`` (several base seeds);
- ``--trial-config``, ``--planner-config``, ``--assets-config``: a whole config;
  ``--set KEY=VALUE``: one value of it changed;
- outputs are named by their format: ``--json PATH``, ``--csv PATH``, ``--png PATH``,
  ``--mjcf DIR``, ``--rerun PATH``;
- ``--scene`` / ``--experiments``: scene kinds (isolated, packed, pile);
- ``--resume``, ``--retry-errors``, ``--force``, ``--no-report``: alike in every command that runs
  trials into a run folder;
- ``--jobs``, ``--executor``, ``--address``: where and how wide trials run.

An old spelling keeps working for one release (:mod:`hsqbench.commands._deprecated`).
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from hsqbench.commands._deprecated import DeprecatedPositional, deprecated

SCENES = ("isolated", "packed", "pile")

PLANNER_SPEC_HELP = (
    "a planner name (`hsqbench planners` lists them) or your own as module:Name or "
    "path/to/file.py:Name"
)

RUN_HELP = "a name under runs/ or a folder path"


def int_at_least(low: int) -> Callable[[str], int]:
    """An argparse type: an integer >= ``low``, or argparse's usage error naming the option."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected a whole number >= {low}, got {text!r}"
            ) from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be >= {low}, got {value}")
        return value

    return parse


#: Seeds (NumPy's generators take no negative one).
non_negative_int = int_at_least(0)
#: ``--jobs`` and counts.
positive_int = int_at_least(1)


def add_jobs(
    parser: argparse.ArgumentParser,
    what: str = "worker processes",
    default: str = "the cores available; 1 runs in this process",
) -> None:
    parser.add_argument(
        "--jobs", type=positive_int, default=None, metavar="N", help=f"{what} (default: {default})"
    )


def add_executor(parser: argparse.ArgumentParser) -> None:
    """``--executor`` and ``--address``: where the trials run, alike in every command that runs
    trials."""
    parser.add_argument(
        "--executor",
        choices=("local", "ray"),
        default="local",
        help="local process pool, or Ray (pip install -e '.[ray]'; same results)",
    )
    parser.add_argument(
        "--address",
        default=None,
        metavar="ADDR",
        help="with --executor ray: join the Ray cluster at ADDR (HOST:PORT printed by `ray start "
        "--head`, or auto) instead of starting a local one; its nodes need hsqbench and the "
        "same HSQ_* paths",
    )


# --- planners ---------------------------------------------------------------------------------


def add_planner(parser: argparse.ArgumentParser, help_text: str, default: str | None) -> None:
    """``--planner PLANNER``: the one planner a command uses (or filters by)."""
    parser.add_argument("--planner", default=default, metavar="PLANNER", help=help_text)


def add_planners(parser: argparse.ArgumentParser, help_text: str, dest: str = "planners") -> None:
    """``--planners PLANNER...``: the planners a command runs or selects."""
    parser.add_argument(
        "--planners", dest=dest, nargs="+", default=None, metavar="PLANNER", help=help_text
    )


# --- run folders ------------------------------------------------------------------------------


def add_run(
    parser: argparse.ArgumentParser,
    help_text: str,
    *,
    default: str | None = None,
    dest: str = "run",
    reads: bool = False,
    positional_alias: bool = False,
) -> None:
    """``--run RUN``. ``reads``: the command reads an existing run, given as a Path
    (:func:`as_path`); ``positional_alias``: the command used to take the run folder as its first
    positional argument (report, replay); that still works, with the note, and ``--run`` is then
    required (checked by :func:`check_required`)."""
    kind = as_path if reads else str
    parser.add_argument(
        "--run", dest=dest, type=kind, default=default, metavar="RUN", help=help_text
    )
    if not reads:
        register_output(parser, dest, "--run", folder=True, resolve=_run_written)
    if positional_alias:
        parser.add_argument(
            dest,
            nargs="?",
            type=kind,
            default=None,
            metavar="RUN",
            action=DeprecatedPositional,
            new="--run RUN",
            help=argparse.SUPPRESS,
        )
        require(parser, dest, "--run RUN")


def require(parser: argparse.ArgumentParser, dest: str, option: str) -> None:
    """Mark ``dest`` as required once both its spellings have been read."""
    required = dict(parser.get_default("_required") or {})
    required[dest] = option
    parser.set_defaults(_required=required, _parser=parser)


def show_required(parser: argparse.ArgumentParser) -> None:
    """Write the options :func:`require` marks without brackets in the usage line (argparse
    brackets them, not knowing they are required). Call once the parser is complete."""
    required = parser.get_default("_required")
    if not required:
        return
    usage = parser.format_usage().removeprefix("usage: ").rstrip("\n")
    for option in required.values():
        usage = usage.replace(f"[{option}]", option)
    parser.usage = usage


def check_required(args: argparse.Namespace) -> None:
    """argparse's usage error (exit 2) for a required option given in neither spelling."""
    for dest, option in (getattr(args, "_required", None) or {}).items():
        if getattr(args, dest, None) is None:
            args._parser.error(f"the following arguments are required: {option}")


def as_path(value: str | Path | None) -> Path | None:
    """A ``--run`` value the command reads, as a Path: a folder path, else a name under runs/."""
    if value is None:
        return None
    path = Path(value)
    if path.exists() or "/" in str(value):
        return path
    from hsqbench.settings import RESULTS_DIR

    return RESULTS_DIR / str(value)


# --- protocols and seeds ----------------------------------------------------------------------


def add_protocol(
    parser: argparse.ArgumentParser, default: str | None = "paper", help_text: str | None = None
) -> None:
    """``--protocol NAME`` (old spelling ``--config``, where ``--config`` named it).
    ``default`` None: no protocol unless one is named (``assets build``)."""
    parser.add_argument(
        "--protocol",
        default=None,
        metavar="NAME",
        help=help_text
        or "benchmark protocol: paper, ycb, quick, ... (configs/protocols/) or a YAML path "
        f"(default: {default})",
    )
    if default is not None:
        deprecated(parser, "--config", "--protocol", "protocol")
        parser.set_defaults(protocol_default=default)


def add_protocols(parser: argparse.ArgumentParser, help_text: str, dest: str = "protocol") -> None:
    """``--protocols NAME...`` (old spelling, in ``sweep``: ``--protocol NAME...``)."""
    parser.add_argument(
        "--protocols", dest=dest, nargs="+", default=None, metavar="NAME", help=help_text
    )
    deprecated(parser, "--protocol", "--protocols", dest, nargs="+")


def protocol_of(args: argparse.Namespace) -> str:
    """The protocol the user named (checked, with a "did you mean"), else the default."""
    from hsqbench.names import check_protocol

    name = args.protocol or args.protocol_default
    check_protocol(name)
    return name


def add_seed(parser: argparse.ArgumentParser, help_text: str, default: int | None = 0) -> None:
    parser.add_argument(
        "--seed", type=non_negative_int, default=default, metavar="N", help=help_text
    )


def add_seeds(parser: argparse.ArgumentParser, help_text: str) -> None:
    parser.add_argument(
        "--seeds", nargs="+", type=non_negative_int, default=None, metavar="N", help=help_text
    )


# --- scenes -----------------------------------------------------------------------------------


def add_scene(parser: argparse.ArgumentParser, default: str, help_text: str) -> None:
    parser.add_argument(
        "--scene",
        choices=SCENES,
        default=default,
        metavar="KIND",
        help=f"{help_text} ({', '.join(SCENES)}; default {default})",
    )


def add_experiments(
    parser: argparse.ArgumentParser,
    help_text: str = "only these experiments",
    default: list[str] | None = None,
    choices: Sequence[str] = SCENES,
) -> None:
    parser.add_argument(
        "--experiments",
        nargs="+",
        choices=choices,
        default=default,
        metavar="KIND",
        help=f"{help_text} (of {', '.join(choices)})",
    )


# --- run control ------------------------------------------------------------------------------


def add_run_control(parser: argparse.ArgumentParser, resume_help: str) -> None:
    """``--resume``, ``--retry-errors``, ``--force``, ``--no-report``: how a command that runs
    trials into a run folder treats what is there, and whether it writes the report after."""
    parser.add_argument("--resume", action="store_true", help=resume_help)
    parser.add_argument(
        "--retry-errors",
        action="store_true",
        help="with --resume, run again the trials that failed with an infrastructure error "
        "(never failed grasps)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="move an existing run folder aside (<name>.replaced-<time>) and start again",
    )
    parser.add_argument(
        "--no-report", action="store_true", help="do not write the tables and plots after the run"
    )


# --- configs and overrides --------------------------------------------------------------------


def add_set(parser: argparse.ArgumentParser, what: str, example: str) -> None:
    """``--set KEY=VALUE`` (repeatable): one value of a config changed for this command."""
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help=f"change this value of the {what} (repeatable), e.g. {example}",
    )


# --- outputs ----------------------------------------------------------------------------------


def add_output(
    parser: argparse.ArgumentParser,
    fmt: str,
    help_text: str,
    *,
    folder: bool = False,
    dest: str | None = None,
) -> None:
    """``--<fmt> PATH`` (a file) or ``--<fmt> DIR`` (a folder): what the command writes, named
    by its format."""
    parser.add_argument(
        f"--{fmt}",
        dest=dest or fmt,
        type=Path,
        default=None,
        metavar="DIR" if folder else "PATH",
        help=help_text,
    )
    extension = {"rerun": "rrd"}.get(fmt, fmt)
    register_output(
        parser,
        dest or fmt,
        f"--{fmt}",
        folder=folder,
        example=f"out.{extension}",
        # The image writer picks the format by it; Rerun's viewer opens .rrd files.
        suffix={"png": ".png", "rerun": ".rrd"}.get(fmt, ""),
    )


def register_output(
    parser: argparse.ArgumentParser,
    dest: str,
    option: str,
    *,
    folder: bool,
    example: str = "",
    suffix: str = "",
    resolve: Any = None,
) -> None:
    """Mark ``dest`` as a path the command writes: :func:`check_outputs` checks it before the
    command starts (``resolve`` turns the value into the path written, e.g. a run name)."""
    outputs = dict(parser.get_default("_outputs") or {})
    outputs[dest] = (option, folder, example, suffix, resolve)
    parser.set_defaults(_outputs=outputs)


def check_outputs(args: argparse.Namespace) -> None:
    """Every output path of the command line, before any work (:mod:`hsqbench.outputs`).

    Raises:
        OutputPathError: one that cannot be written as asked.
    """
    from hsqbench.outputs import check_output

    outputs = getattr(args, "_outputs", None) or {}
    for dest, (option, folder, example, suffix, resolve) in outputs.items():
        value = getattr(args, dest, None)
        if value is not None:
            path = resolve(value) if resolve is not None else value
            check_output(path, folder=folder, option=option, example=example, suffix=suffix)


def _run_written(value: str) -> Path:
    """The folder a writing command's ``--run`` names (a name goes under runs/)."""
    from hsqbench.runs import run_folder

    return run_folder(value, "")
