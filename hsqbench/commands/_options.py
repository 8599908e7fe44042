"""The options several commands share, defined once so that each means the same everywhere.

- ``--protocol``: a benchmark protocol (``paper``, ``quick`` or a YAML path);
- ``--trial-config``, ``--planner-config``: the config of one trial, of one planner;
- ``--scene``: a scene kind (isolated, packed, pile);
- ``--jobs``: worker processes, a positive integer, checked when the command line is read;
- ``--planner`` / ``--planners``: names or plugin specs (``module:Name``, ``file.py:Name``).

An old spelling (``--config``, ``--kind``) keeps working for one release, with a one-line
deprecation note on stderr.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any

SCENES = ("isolated", "packed", "pile")

PLANNER_SPEC_HELP = (
    "a planner name (`hsqbench planners` lists them) or your own as module:Name or "
    "path/to/file.py:Name"
)


class _Deprecated(argparse.Action):
    """Stores like the new option, after a one-line note that the old spelling goes."""

    def __init__(self, option_strings: Sequence[str], dest: str, new: str = "", **kw: Any):
        self.new = new
        super().__init__(option_strings, dest, **kw)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        print(
            f"hsqbench: {option_string} is deprecated here, use {self.new} (the old spelling "
            "will be removed in the next release)",
            file=sys.stderr,
        )
        setattr(namespace, self.dest, values)


def deprecated(parser: argparse.ArgumentParser, old: str, new: str, dest: str, **kw: Any) -> None:
    """Accept ``old`` as a hidden, deprecated spelling of ``new`` (same ``dest``)."""
    parser.add_argument(
        old, dest=dest, action=_Deprecated, new=new, help=argparse.SUPPRESS, default=None, **kw
    )


def positive_int(text: str) -> int:
    """An integer >= 1 (for ``--jobs`` and counts), or argparse's usage error."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


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


def add_protocol(parser: argparse.ArgumentParser, default: str = "paper") -> None:
    """``--protocol NAME`` (old spelling ``--config``)."""
    parser.add_argument(
        "--protocol",
        default=None,
        metavar="NAME",
        help="benchmark protocol: paper, ycb, quick, ... (configs/protocols/) or a YAML path "
        f"(default: {default})",
    )
    deprecated(parser, "--config", "--protocol", "protocol")
    parser.set_defaults(protocol_default=default)


def protocol_of(args: argparse.Namespace) -> str:
    """The protocol the user named (checked, with a "did you mean"), else the default."""
    from hsqbench.names import check_protocol

    name = args.protocol or args.protocol_default
    check_protocol(name)
    return name


def add_scene(parser: argparse.ArgumentParser, default: str, help_text: str) -> None:
    parser.add_argument("--scene", choices=SCENES, default=default, help=help_text)
