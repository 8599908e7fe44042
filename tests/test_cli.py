"""The command line's error handling (hsqbench.cli): input errors are one line and exit 2;
internal errors keep their traceback."""

from __future__ import annotations

import pytest

from hsqbench import cli
from hsqbench.commands import report


def test_input_errors_are_one_line_and_exit_2(monkeypatch, capsys) -> None:
    def bad_input(args):
        raise ValueError("--thing must be > 0, got -1")

    monkeypatch.setattr(report, "run", bad_input)
    assert cli.main(["report", "--run", "somewhere"]) == 2
    err = capsys.readouterr().err
    assert err.strip() == "hsqbench report: error: --thing must be > 0, got -1"


def test_internal_errors_keep_their_traceback(monkeypatch) -> None:
    def bug(args):
        raise RuntimeError("an internal invariant broke")

    monkeypatch.setattr(report, "run", bug)
    with pytest.raises(RuntimeError, match="invariant") as info:
        cli.main(["report", "--run", "somewhere"])
    assert info.traceback[-1].name == "bug"
    monkeypatch.setattr(report, "run", lambda args: {}["missing"])
    with pytest.raises(KeyError):
        cli.main(["report", "--run", "somewhere"])
