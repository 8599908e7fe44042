"""Every path a command writes is checked before it starts: one line, exit 2, nothing run and
nothing written (a trial's result was lost to `--json DIR` after the whole trial ran)."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

from hsqbench.cli import build_parser, main
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig
from hsqbench.experiment.runner import run_benchmark
from hsqbench.outputs import OutputPathError, check_output
from tests.cli_parsers import command_parsers
from tests.fake_backend import FakeBackend

REPO = Path(__file__).resolve().parents[1]
#: The options that name what a command writes (docs/cli.md: outputs are named by format).
OUTPUT_OPTIONS = {"--json", "--csv", "--png", "--mjcf", "--rerun", "--dest"}
#: Commands whose --run is a folder they write (the others read one).
WRITES_RUN = {"benchmark", "ablate", "sweep"}


def test_every_output_option_of_every_command_is_checked() -> None:
    for name, parser in command_parsers(build_parser()):
        options = {o for a in parser._actions for o in a.option_strings}
        wanted = {o for o in options if o in OUTPUT_OPTIONS}
        if "--run" in options and name in WRITES_RUN:
            wanted.add("--run")
        registered = {spec[0] for spec in (parser.get_default("_outputs") or {}).values()}
        assert registered == wanted, name


@pytest.fixture
def places(tmp_path, monkeypatch):
    folder = tmp_path / "folder"
    folder.mkdir()
    (tmp_path / "file").write_text("x")
    monkeypatch.chdir(tmp_path)
    return tmp_path


CASES = [
    ("trial", ["--object", "mug", "--json", "folder"], "--json folder: is a folder"),
    ("trial", ["--object", "mug", "--rerun", "folder"], "--rerun folder: is a folder"),
    ("trial", ["--object", "mug", "--json", "file/out.json"], "file is a file, so nothing"),
    ("plan", ["cloud.npy", "--json", "folder"], "--json folder: is a folder"),
    ("scene", ["--png", "folder"], "--png folder: is a folder"),
    ("scene", ["--png", "shot.jpg"], "needs the .png extension, e.g. shot.png"),
    ("trial", ["--object", "mug", "--rerun", "ep.txt"], "needs the .rrd extension, e.g. ep.rrd"),
    ("scene", ["--mjcf", "file"], "--mjcf file: is a file, not a folder"),
    ("replay", ["--run", "somewhere", "--csv", "folder"], "--csv folder: is a folder"),
    ("benchmark", ["--run", "./file"], "--run file: is a file, not a folder"),
    ("benchmark", ["--run", "./file/run"], "file is a file, so nothing"),
    ("benchmark", ["--rerun", "file"], "--rerun file: is a file, not a folder"),
    ("ablate", ["--run", "./file"], "--run file: is a file, not a folder"),
    ("sweep", ["depth_noise", "--run", "./file"], "--run file: is a file, not a folder"),
    ("assets", ["download", "--dest", "file", "mug"], "--dest file: is a file, not a folder"),
]


@pytest.mark.parametrize(("command", "argv", "message"), CASES, ids=lambda c: str(c)[:40])
def test_a_bad_output_path_stops_the_command_before_it_runs(
    places, monkeypatch, capsys, command, argv, message
) -> None:
    module = importlib.import_module(f"hsqbench.commands.{command}")

    def ran(args):
        raise AssertionError(f"{command} ran with an output path it cannot write")

    monkeypatch.setattr(module, "run", ran)
    before = sorted(p.name for p in places.rglob("*"))
    assert main([command, *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert sorted(p.name for p in places.rglob("*")) == before  # nothing written


def test_good_output_paths_pass(places) -> None:
    assert check_output("new/deeper/out.json", folder=False, option="--json")
    assert check_output("file", folder=False, option="--json")  # overwritten, as before
    assert check_output("folder", folder=True, option="--mjcf")
    assert check_output("new/run", folder=True, option="--run")
    assert not (places / "new").exists()  # a check creates nothing


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_an_unwritable_folder_is_named(places) -> None:
    locked = places / "locked"
    locked.mkdir(mode=0o500)
    with pytest.raises(OutputPathError, match="locked is not writable"):
        check_output(locked / "out.json", folder=False, option="--json")


def test_the_python_api_checks_its_run_folder_first(tmp_path) -> None:
    (tmp_path / "taken").write_text("not a run")
    config = ExperimentConfig(planners=("a",), isolated=IsolatedConfig(objects=("mug",)))
    backend = FakeBackend(raise_on=("mug",))  # a trial that ran would raise, not this error
    with pytest.raises(OutputPathError, match=r"run folder .*taken: is a file"):
        run_benchmark(config, tmp_path / "taken", backend=backend, progress=False)
    assert backend.prepared == ()  # no work started


def test_python_m_hsqbench_cli_reports_a_command_error_in_one_line(tmp_path) -> None:
    """`make benchmark` runs `python -m hsqbench.cli`: there too an input error is one line."""
    done = subprocess.run(
        [sys.executable, "-m", "hsqbench.cli", "benchmark", "--retry-errors"],
        capture_output=True,
        text=True,
        cwd=REPO,
        env={**os.environ, "PYTHONPATH": str(REPO)},
    )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "hsqbench benchmark: error: --retry-errors only applies with --resume --run RUN"
    ]
