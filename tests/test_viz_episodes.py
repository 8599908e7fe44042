"""Recording a benchmark run's trials afterwards: choosing trials, and a replay that reproduces
the run's outcome into a readable recording."""

from __future__ import annotations

import pytest

from hsqbench.config import from_dict
from hsqbench.experiment.config import ExperimentConfig
from hsqbench.experiment.runner import run_benchmark
from hsqbench.viz.episodes import choose_trials, record_run, run_trial_config
from hsqbench.viz.rrd import read_recording
from tests.fake_backend import FakeBackend


def _config(objects, attempts, packed=False, trial_config="trial") -> ExperimentConfig:
    return from_dict(
        ExperimentConfig,
        {
            "planners": ["hsq"],
            "seeds": [0],
            "trial_config": trial_config,
            "isolated": {"objects": list(objects), "attempts_per_object": attempts},
            "packed": {
                "enabled": packed,
                "objects": list(objects),
                "rounds": 1,
                "objects_per_round": min(2, len(objects)),
            },
        },
    )


def test_choose_failures_all_and_keys(tmp_path):
    run = tmp_path / "fake"
    config = _config(["a", "b", "c"], 4, packed=True)
    run_benchmark(config, run, backend=FakeBackend(default_success=0.5), progress=False)
    every = choose_trials(run, "all")
    assert len(every) == 3 * 4 + 1
    failed = choose_trials(run, "failures")
    assert failed and len(failed) < len(every)
    assert all(c.failed for c in failed)
    assert {c.key for c in every if c.failed} == {c.key for c in failed}
    packed = [c for c in every if c.experiment == "packed"]
    assert len(packed) == 1 and len(packed[0].objects) == 2
    assert choose_trials(run, "failures", limit=1) == failed[:1]
    key = every[5].key
    assert choose_trials(run, keys=[key]) == [every[5]]
    assert every[5].filename.endswith(".rrd") and "/" not in every[5].filename
    with pytest.raises(ValueError, match="no finished trial"):
        choose_trials(run, keys=["isolated/hsq/s0/zzz/000"])
    with pytest.raises(ValueError, match="failures"):
        choose_trials(run, "some")
    # The fake backend stores no trial config: its runs cannot be replayed.
    with pytest.raises(ValueError, match="no trial config"):
        run_trial_config(run)


def test_replay_reproduces_the_run_into_a_recording(tmp_path):
    trial_yaml = tmp_path / "trial_surface.yaml"
    trial_yaml.write_text("sensor: surface\n")  # the fast stand-in sensor
    run = tmp_path / "sim"
    run_benchmark(_config(["proc_box"], 1, trial_config=str(trial_yaml)), run, progress=False)
    assert run_trial_config(run).sensor == "surface"
    seen = []
    episodes = record_run(run, tmp_path / "rrd", "all", report=seen.append)
    assert len(episodes) == 1 and seen == episodes
    episode = episodes[0]
    assert episode.matches, (episode.outcomes, episode.choice.outcomes)
    summary = read_recording(episode.path)
    assert episode.path.name == "isolated_hsq_s0_proc_box_000.rrd"
    assert "world/objects/proc_box" in summary.entity_paths
    assert episode.choice.outcomes[0] in summary.texts["outcome"]


def test_a_run_made_before_the_config_tree_still_replays() -> None:
    """A run recorded with config names and planner_config: null (its run.json, kept in
    tests/data): its replay config is today's tree with the recorded values."""
    from pathlib import Path

    from hsqbench.sim.trial import load_trial_config

    old = run_trial_config(Path(__file__).parent / "data" / "run_before_config_tree")
    assert old.planners == load_trial_config().planners
    assert old.scene == load_trial_config().scene and old.max_ranks == 48
