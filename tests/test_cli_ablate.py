"""``hsqbench ablate``: the planner list it builds and hands to the benchmark runner."""

from __future__ import annotations

from dataclasses import replace

import pytest

from hsqbench.cli import main
from hsqbench.commands.ablate import ablation_planner_list
from hsqbench.planner.hsq.additions import ADDITIONS, AdditionsConfig
from hsqbench.planner.hsq.config import load_planner_config
from hsqbench.planner.registry import planner_names


def test_the_list_is_hsq_the_paper_and_one_planner_per_addition(capsys) -> None:
    names = ablation_planner_list(None)
    assert names[:2] == ["hsq", "hsq-paper"]
    on = [a for a in AdditionsConfig.names() if a not in load_planner_config().additions.off()]
    # Superseded additions (support_facing, while hidden_bodies is on) are left out, and said so.
    superseded = [a for a in on if ADDITIONS[a].superseded_by in on]
    assert superseded == ["support_facing"]
    assert names[2:] == [f"hsq-no-{a.replace('_', '-')}" for a in on if a not in superseded]
    assert "leaving out hsq-no-support-facing: hidden_bodies" in capsys.readouterr().err
    assert "hsq-no-support-facing" in ablation_planner_list(["support_facing"])
    assert set(names) <= set(planner_names())
    assert ablation_planner_list(["sweep"], ("antipodal",)) == [
        "hsq",
        "hsq-paper",
        "hsq-no-sweep",
        "antipodal",
    ]
    with pytest.raises(ValueError, match="unknown addition"):
        ablation_planner_list(["no_such_thing"])


def test_an_addition_off_by_default_is_not_ablated(monkeypatch) -> None:
    """hsq-no-<name> of a switch the default config has off would be hsq itself."""
    import hsqbench.planner.hsq.config as planner_config

    loaded = load_planner_config()
    off = replace(loaded, additions=replace(loaded.additions, sweep=False))
    monkeypatch.setattr(planner_config, "load_planner_config", lambda *a, **k: off)
    assert "hsq-no-sweep" not in ablation_planner_list(None)
    with pytest.raises(ValueError, match=r"\['sweep'\] are off in configs/planner.yaml"):
        ablation_planner_list(["sweep"])


def test_a_superseded_addition_is_ablated_when_its_successor_is_off(monkeypatch) -> None:
    import hsqbench.planner.hsq.config as planner_config

    loaded = load_planner_config()
    off = replace(loaded, additions=replace(loaded.additions, hidden_bodies=False))
    monkeypatch.setattr(planner_config, "load_planner_config", lambda *a, **k: off)
    names = ablation_planner_list(None)
    assert "hsq-no-support-facing" in names and "hsq-no-hidden-bodies" not in names


def test_the_command_runs_the_benchmark_with_that_list(monkeypatch, tmp_path) -> None:
    seen = {}

    class Summary:
        selected = skipped = ran = errors = planner_errors = 0
        config_hash = "x"

    def fake_run(config, run_dir, **kwargs):
        seen["planners"] = config.planners
        seen["run_dir"] = run_dir
        return Summary()

    monkeypatch.setattr("hsqbench.experiment.runner.run_benchmark", fake_run)
    run = tmp_path / "abl"
    code = main(
        [
            "ablate",
            "--protocol",
            "quick",
            "--run",
            str(run),
            "--additions",
            "sweep",
            "caps",
            "--no-report",
        ]
    )
    assert code == 0
    assert seen["planners"] == ("hsq", "hsq-paper", "hsq-no-sweep", "hsq-no-caps")
    assert str(seen["run_dir"]) == str(run)
