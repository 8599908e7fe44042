"""docs/cli.md is the command line's vocabulary: every option of every command (its parser, read
here) is in its table, spelled and formatted as the table says, in exactly the commands it
lists; every old spelling is listed there, behaves as its replacement and says which that is."""

from __future__ import annotations

import argparse
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from hsqbench.cli import build_parser
from hsqbench.commands._deprecated import deprecated_aliases
from tests.cli_parsers import command_parsers

DOC = Path(__file__).resolve().parents[1] / "docs" / "cli.md"

#: What a command needs besides the option under test to parse (its positional arguments).
_TAIL = {
    "plan": ["cloud.npy"],
    "compare": ["a", "b"],
    "view": ["episode.rrd"],
    "assets": ["list"],
    "assets import": ["meshes"],
}


@dataclass
class Row:
    idea: str
    spelling: str  # as the table writes it: `--planners PLANNER...`, `CLOUD`
    commands: set[str]
    old: dict[str, set[str]] = field(default_factory=dict)  # old spelling -> its commands

    @property
    def name(self) -> str:
        return self.spelling.split()[0]


def _table() -> list[Row]:
    rows = []
    for line in DOC.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or not cells[1].startswith("`"):
            continue
        idea, spelling, commands, old = cells
        row = Row(idea, spelling.strip("`"), {c.strip() for c in commands.split(",")})
        for name, where in re.findall(r"`([^`]+)` \(([^)]+)\)", old):
            row.old[name] = {c.strip() for c in where.split(",")}
        rows.append(row)
    return rows


def _own_actions(parser: argparse.ArgumentParser):
    """The parser's options and positionals, less help, sub-commands and old spellings."""
    old = set(deprecated_aliases(parser))
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction | argparse._SubParsersAction):
            continue
        key = action.option_strings[0] if action.option_strings else action.metavar
        if key in old or action.help == argparse.SUPPRESS:
            continue
        yield action


def _spelling(action: argparse.Action) -> str:
    """An option as the table writes it: name, then its value (``NAME...`` for several)."""
    if action.option_strings and action.nargs == 0:
        return action.option_strings[0]
    metavar = action.metavar
    if metavar is None:
        metavar = "{" + ",".join(action.choices) + "}" if action.choices else action.dest.upper()
    value = " ".join(metavar) if isinstance(metavar, tuple) else metavar
    if action.nargs in ("+", "*"):
        value += "..."
    return f"{action.option_strings[0]} {value}" if action.option_strings else value


def test_every_option_of_every_command_is_in_the_table_as_it_is_spelled():
    rows = {r.name: r for r in _table() if not r.spelling.startswith("hsqbench ")}
    problems = []
    for path, parser in command_parsers(build_parser()):
        for action in _own_actions(parser):
            if len(action.option_strings) > 1:
                problems.append(f"{path}: {action.option_strings} is one option, two names")
            spelling = _spelling(action)
            row = rows.get(spelling.split()[0])
            if row is None:
                problems.append(f"{path}: {spelling} is not in docs/cli.md")
            elif path not in row.commands:
                problems.append(f"{path}: {spelling} is not listed for this command")
            elif spelling != row.spelling:
                problems.append(f"{path}: {spelling}, docs/cli.md says {row.spelling}")
    assert problems == []


def test_every_command_the_table_lists_has_the_option():
    options = {
        path: {_spelling(a).split()[0] for a in _own_actions(parser)}
        for path, parser in command_parsers(build_parser())
    }
    missing = [
        f"{command}: {row.spelling}"
        for row in _table()
        if not row.spelling.startswith("hsqbench ")
        for command in sorted(row.commands)
        if row.name not in options.get(command, ())
    ]
    assert missing == []


def _aliases() -> list[tuple[str, str, str]]:
    """(command path, old spelling, new spelling) of every old spelling the parsers accept."""
    return [
        (path, old, new)
        for path, parser in command_parsers(build_parser())
        for old, new in deprecated_aliases(parser).items()
    ]


def test_every_old_spelling_is_in_the_table_beside_its_replacement():
    rows = _table()
    accepted = {(path, old) for path, old, _ in _aliases()}
    problems = []
    for path, old, new in _aliases():
        row = next((r for r in rows if new in (r.spelling, r.name)), None)
        if row is None:
            row = next((r for r in rows if r.name == new.split()[0]), None)
        if row is None or path not in row.old.get(old, set()):
            problems.append(f"{path}: {old} (now {new}) is not an old spelling of its row")
    listed = {(c, old) for r in rows for old, where in r.old.items() for c in where}
    problems += [f"{c}: {old} is listed but not accepted" for c, old in sorted(listed - accepted)]
    assert problems == []


def _sample(action: argparse.Action) -> list[str]:
    """Values to give an option in a test."""
    if action.nargs == 0:
        return []
    if action.choices:
        return [list(action.choices)[-1]]
    return ["3"] if action.type is int else ["x.yaml"]


@pytest.mark.parametrize(("path", "old", "new"), _aliases(), ids=lambda v: str(v))
def test_an_old_spelling_parses_as_the_new_one_with_one_line_naming_it(path, old, new, capsys):
    parser = dict(command_parsers(build_parser()))[path]
    action = next(
        a
        for a in parser._actions
        if (a.option_strings[:1] or [a.metavar]) == [old] and getattr(a, "new", None) == new
    )
    head, tail = path.split(), _TAIL.get(path, [])
    values = _sample(action)
    old_argv = [*head, *([old] if action.option_strings else []), *values, *tail]
    old_args = build_parser().parse_args(old_argv)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"use {new}" in err[0] and "deprecated" in err[0], err
    if new.startswith("hsqbench "):  # the idea moved to another command
        return
    new_words = new.split()
    new_values = values if len(new_words) == 1 or new_words[1].isupper() else new_words[1:]
    new_argv = [*head, new_words[0], *new_values, *tail]
    new_args = build_parser().parse_args(new_argv)
    assert capsys.readouterr().err == ""
    assert _values(old_args) == _values(new_args)


def _values(args: argparse.Namespace) -> dict:
    return {k: v for k, v in vars(args).items() if k != "_parser"}  # each parse builds its own


def test_a_run_folder_is_given_once():
    with pytest.raises(SystemExit) as exit_:
        build_parser().parse_args(["report", "--run", "runs/a", "runs/b"])
    assert exit_.value.code == 2


@pytest.mark.parametrize("command", ["report", "replay"])
def test_commands_that_read_a_run_require_it(command, capsys):
    from hsqbench.cli import main

    with pytest.raises(SystemExit) as exit_:
        main([command])
    assert exit_.value.code == 2
    assert "the following arguments are required: --run RUN" in capsys.readouterr().err


#: Where commands are written for users: none may use an old spelling. docs/changes.md is history
#: and docs/cli.md lists the old spellings on purpose.
_WRITTEN = ("README.md", "Makefile", "docs", "examples", "configs", "bench", "hsqbench")
_COMMAND = re.compile(r"hsqbench(?:\.cli)?\s+([a-z]+)\b([^`\n#\"]*)")


def _written_commands():
    root = DOC.parents[1]
    for top in _WRITTEN:
        base = root / top
        files = [base] if base.is_file() else sorted(p for p in base.rglob("*") if p.is_file())
        for path in files:
            if path.name in ("changes.md", "cli.md") or path.suffix not in (
                ".md",
                ".py",
                ".yaml",
                ".toml",
                ".txt",
                "",
            ):
                continue
            for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
                for m in _COMMAND.finditer(line):
                    yield f"{path.relative_to(root)}:{n}", m.group(1), m.group(2).split()


def test_readme_docs_examples_and_help_use_only_the_new_spellings():
    parsers = dict(command_parsers(build_parser()))
    problems = []
    for where, command, words in _written_commands():
        if command not in parsers:
            continue
        path = command
        if words and f"{command} {words[0]}" in parsers:  # assets ACTION
            path = f"{command} {words[0]}"
        old = set(deprecated_aliases(parsers[path])) | set(deprecated_aliases(parsers[command]))
        for word in words:
            name = word.split("=")[0]
            if name.startswith("--") and name in old:
                problems.append(f"{where}: hsqbench {command} ... {name}")
        if "RUN" in old and words and not words[0].startswith("-"):
            problems.append(f"{where}: hsqbench {command} {words[0]} (a run is --run RUN)")
    assert problems == []
