"""One CLI language: shared options mean and check the same everywhere, old spellings still
work with a one-line note, misspelt names get the closest one, and every option has help."""

from __future__ import annotations

import argparse

import pytest

import hsqbench.planner.learned.network as network
from hsqbench.cli import build_parser, main
from hsqbench.commands import _options
from tests.cli_parsers import command_parsers


def test_every_option_of_every_command_has_help():
    root = build_parser()
    missing = [
        f"{path} {action.option_strings or action.dest}"
        for path, parser in [("hsqbench", root), *command_parsers(root)]
        for action in parser._actions
        if action.help is None and not isinstance(action, argparse._SubParsersAction)
    ]
    assert missing == []


@pytest.mark.parametrize(
    "argv",
    [
        ["benchmark", "--jobs", "0"],
        ["ablate", "--jobs", "-1"],
        ["sweep", "depth_noise", "--jobs", "two"],
        ["assets", "build", "--all", "--jobs", "0"],
    ],
)
def test_jobs_is_checked_alike_when_the_command_line_is_read(argv, capsys):
    with pytest.raises(SystemExit) as exit_:
        build_parser().parse_args(argv)
    assert exit_.value.code == 2
    assert "--jobs: " in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "dest", "value", "new"),
    [
        (["benchmark", "--config", "quick"], "protocol", "quick", "--protocol"),
        (["ablate", "--config", "quick"], "protocol", "quick", "--protocol"),
        (["trial", "--config", "trial_resting"], "trial_config", "trial_resting", "--trial-config"),
        (["plan", "c.npy", "--config", "planner"], "planner_config", "planner", "--planner-config"),
        (["scene", "--kind", "pile"], "scene", "pile", "--scene"),
        (["assets", "--config", "x.yaml", "list"], "assets_config", "x.yaml", "--assets-config"),
    ],
)
def test_old_spellings_work_with_one_line_saying_the_new_one(argv, dest, value, new, capsys):
    args = build_parser().parse_args(argv)
    assert getattr(args, dest) == value
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{argv[1 if argv[0] != 'plan' else 2]} is deprecated" in err[0]
    assert f"use {new}" in err[0]


def test_new_spellings_parse_silently(capsys):
    args = build_parser().parse_args(["benchmark", "--protocol", "quick", "--jobs", "2"])
    assert (args.protocol, args.jobs) == ("quick", 2)
    assert build_parser().parse_args(["scene", "--scene", "isolated"]).scene == "isolated"
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["benchmark", "--protocol", "quik"], "no protocol 'quik' (did you mean 'quick'?)"),
        (["benchmark", "--planners", "hqs"], "unknown planner 'hqs' (did you mean 'hsq'?)"),
        (["trial", "--planner", "antipodel", "--object", "mug"], "(did you mean 'antipodal'?)"),
        (["trial", "--object", "proc_cylindr"], "(did you mean 'proc_cylinder'?)"),
        (["trial", "--planner", "nowhere.py:X", "--object", "mug"], "no file nowhere.py"),
    ],
)
def test_misspelt_names_get_one_line_with_the_closest(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_a_benchmark_resumed_with_other_planners_says_which_to_give(tmp_path, capsys):
    run = tmp_path / "r"
    run.mkdir()
    (run / "run.json").write_text('{"config": {"planners": ["hsq", "topdown"]}, "backend": {}}')
    assert main(["benchmark", "--protocol", "quick", "--run", str(run), "--resume"]) == 2
    assert "resume it with --planners hsq topdown" in capsys.readouterr().err


def test_a_resume_refusal_names_the_planners_the_run_holds(tmp_path, capsys):
    """A run of `--planners toppick` on a protocol of hsq: its planner list is hsq, toppick,
    but it holds toppick's trials only, and --planners toppick resumes it."""
    from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig
    from hsqbench.experiment.runner import run_benchmark
    from tests.fake_backend import FakeBackend

    run = tmp_path / "r"
    config = ExperimentConfig(
        planners=("hsq", "toppick"), isolated=IsolatedConfig(objects=("mug",))
    )
    run_benchmark(config, run, backend=FakeBackend(), planners=["toppick"], progress=False)
    argv = ["benchmark", "--protocol", "quick", "--run", str(run), "--resume"]
    assert main([*argv, "--planners", "antipodal"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{run} holds trials of toppick (planner list hsq, toppick)" in err
    assert "this command runs antipodal (planner list hsq, antipodal)" in err
    assert err.endswith("resume it with --planners toppick (or start another --run)")


def test_planners_lists_each_planner_on_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(network, "available", lambda: False)
    spec = tmp_path / "mine.py"
    spec.write_text(
        "from hsqbench.planner.base import PlannerBase\n\nclass Mine(PlannerBase):\n"
        "    name = 'mine-listed'\n\n    def stages(self, clean, context):\n        pass\n"
    )
    assert main(["planners", f"{spec}:Mine"]) == 0
    lines = {line.split()[0]: line for line in capsys.readouterr().out.splitlines()}
    assert "built-in" in lines["hsq"] and "privileged" in lines["oracle"]
    assert (
        "needs extra" in lines["contact-graspnet"] and "make learned" in lines["contact-graspnet"]
    )
    assert "plugged in" in lines["mine-listed"] and str(spec.resolve()) in lines["mine-listed"]


@pytest.mark.parametrize(
    "argv",
    [["benchmark"], ["ablate"], ["sweep", "cameras"]],
    ids=["benchmark", "ablate", "sweep"],
)
def test_every_command_that_runs_trials_takes_the_same_executor_options(argv):
    args = build_parser().parse_args([*argv, "--executor", "ray", "--address", "auto"])
    assert (args.executor, args.address) == ("ray", "auto")
    with pytest.raises(SystemExit):
        build_parser().parse_args([*argv, "--executor", "threads"])


def test_positive_int_accepts_whole_numbers_from_one():
    assert _options.positive_int("3") == 3
    for bad in ("0", "-2", "1.5"):
        with pytest.raises(argparse.ArgumentTypeError):
            _options.positive_int(bad)


def test_every_built_in_planner_has_its_line():
    from hsqbench.planner.hsq.additions import ablation_planners
    from hsqbench.planner.registry import DESCRIPTIONS, is_builtin, planner_names

    builtin = {n for n in planner_names() if is_builtin(n)} - set(ablation_planners())
    assert builtin <= set(DESCRIPTIONS), builtin - set(DESCRIPTIONS)


class _Captured(Exception):
    """Raised by a stand-in to hand back what the command passed on, before any trial runs."""


def test_benchmark_and_ablate_take_base_seeds_and_ablate_retries_errors(tmp_path, monkeypatch):
    import hsqbench.experiment.runner as runner

    def capture(config, run_dir, **kw):
        raise _Captured(config, kw)

    monkeypatch.setattr(runner, "run_benchmark", capture)
    run = str(tmp_path / "r")
    with pytest.raises(_Captured) as got:
        main(["benchmark", "--protocol", "quick", "--run", run, "--seeds", "7", "8", "--jobs", "1"])
    assert got.value.args[0].seeds == (7, 8)
    with pytest.raises(_Captured) as got:
        main(["ablate", "--protocol", "quick", "--run", run, "--seeds", "9", "--jobs", "1",
              "--additions", "caps", "--resume", "--retry-errors"])  # fmt: skip
    config, kw = got.value.args
    assert config.seeds == (9,) and kw["retry_errors"] and kw["resume"]
    assert main(["ablate", "--protocol", "quick", "--run", run, "--retry-errors"]) == 2


def test_trial_set_changes_one_value_of_the_trial_config(monkeypatch, capsys):
    import hsqbench.sim.trial as sim_trial

    def capture(obj, seed, planner, config, recorder=None):
        raise _Captured(config)

    monkeypatch.setattr(sim_trial, "run_isolated_trial", capture)
    with pytest.raises(_Captured) as got:
        main(["trial", "--object", "mug", "--set", "execution.lift_height_m=0.123"])
    assert got.value.args[0].execution.lift_height_m == 0.123
    assert main(["trial", "--object", "mug", "--set", "execution.lift_heigth_m=1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "lift_heigth_m" in err


@pytest.mark.parametrize(
    "argv",
    [
        ["trial", "--object", "mug", "--seed", "-1"],
        ["scene", "--seed", "-3"],
        ["plan", "cloud.npy", "--seed", "-2"],
        ["benchmark", "--seeds", "0", "-1"],
    ],
)
def test_a_negative_seed_is_a_usage_error_naming_the_option(argv, capsys):
    """It reached NumPy's generator and came back as 'expected non-negative integer'."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    option = "--seeds" if "--seeds" in argv else "--seed"
    assert f"argument {option}: must be >= 0, got -" in capsys.readouterr().err
