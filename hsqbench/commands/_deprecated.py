"""Old option spellings kept working for one release.

An old spelling stores exactly what the new one does, after one line on stderr naming the new
one; it is hidden from ``--help``. docs/cli.md lists every old spelling, and
tests/test_cli_vocabulary.py reads them from the parsers with :func:`deprecated_aliases`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import Any


def _note(old: str, new: str) -> None:
    print(
        f"hsqbench: {old} is deprecated, use {new} (the old spelling will be removed in the "
        "next release)",
        file=sys.stderr,
    )


class _Deprecated(argparse.Action):
    """Stores like the new option, after a one-line note that the old spelling goes. With
    ``nargs=0`` (an old on/off flag such as ``--packed``) it stores ``const``."""

    def __init__(self, option_strings: Sequence[str], dest: str, new: str = "", **kw: Any):
        self.new = new
        super().__init__(option_strings, dest, **kw)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        _note(option_string or self.dest, self.new)
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


class DeprecatedPositional(argparse.Action):
    """A positional argument that became an option (``report RUN`` -> ``report --run RUN``):
    accepted, with the note, when given; silent when absent."""

    def __init__(self, option_strings: Sequence[str], dest: str, new: str = "", **kw: Any):
        self.new = new
        super().__init__(option_strings, dest, **kw)

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        if values is None or values == self.default:
            return
        _note(f"the positional {self.metavar}", self.new)
        if getattr(namespace, self.dest, None) not in (None, self.default):
            parser.error(f"give the run folder once, as {self.new}")
        setattr(namespace, self.dest, values)


def deprecated(
    parser: argparse.ArgumentParser,
    old: str,
    new: str,
    dest: str,
    *,
    flag: Any = None,
    default: Any = None,
    **kw: Any,
) -> None:
    """Accept ``old`` as a hidden, deprecated spelling of ``new`` (same ``dest``). ``flag``: the
    value an old on/off switch stands for (``--packed`` is ``--scene packed``)."""
    if flag is not None:
        kw.update(nargs=0, const=flag)
    parser.add_argument(
        old, dest=dest, action=_Deprecated, new=new, help=argparse.SUPPRESS, default=default, **kw
    )


def deprecated_aliases(parser: argparse.ArgumentParser) -> dict[str, str]:
    """``{old spelling: new spelling}`` of one parser (for docs/cli.md's test)."""
    return {
        (a.option_strings[0] if a.option_strings else a.metavar): a.new
        for a in parser._actions
        if isinstance(a, _Deprecated | DeprecatedPositional)
    }
