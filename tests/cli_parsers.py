"""Every parser of the command line, for tests that check all commands alike."""

from __future__ import annotations

import argparse


def command_parsers(parser: argparse.ArgumentParser, path: str = ""):
    """(path, parser) of every command and every action of a command below ``parser``."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                here = f"{path} {name}".strip()
                yield here, sub
                yield from command_parsers(sub, here)
