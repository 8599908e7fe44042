"""The default backend calls the trial runner's contract; a missing runner is said plainly."""

from __future__ import annotations

import pickle
import sys
import types
from dataclasses import dataclass

import pytest

from hsqbench.experiment.backend import (
    SimBackend,
    TrialRunnerUnavailable,
    execute_trial,
    presentation_groups,
)
from hsqbench.experiment.seeds import TrialSpec
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult, TrialResult


@dataclass(frozen=True)
class _TrialConfig:
    settle_s: float = 0.5


def _trial_module(calls: list) -> types.ModuleType:
    mod = types.ModuleType("hsqbench.sim.trial")
    mod.TrialConfig = _TrialConfig

    def run_isolated_trial(obj, seed, planner, config):
        calls.append(("isolated", obj, seed, planner, config))
        return TrialResult(obj, seed, planner, [Attempt(Outcome.SUCCESS, target=obj)])

    def run_packed_round(objects, seed, planner, config):
        calls.append(("packed", tuple(objects), seed, planner, config))
        return RoundResult(objects, seed, planner, [Attempt(Outcome.DROPPED)] * 2, [])

    mod.run_isolated_trial = run_isolated_trial
    mod.run_packed_round = run_packed_round
    return mod


def test_sim_backend_passes_the_loaded_trial_config(tmp_path, monkeypatch) -> None:
    calls: list = []
    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", _trial_module(calls))
    path = tmp_path / "trial.yaml"
    path.write_text("settle_s: 0.25\n")
    backend = SimBackend(str(path))
    backend.check(("hsq",))
    assert backend.fingerprint()["trial_config"] == {"settle_s": 0.25}
    run = execute_trial(backend, TrialSpec("isolated", "hsq", 0, 0, ("mug",), 7))
    assert run.ok and run.result.success
    run = execute_trial(backend, TrialSpec("packed", "hsq", 0, 0, ("mug", "bowl"), 8))
    assert run.ok and run.result.clearance_rate == 0.0
    assert calls == [
        ("isolated", "mug", 7, "hsq", _TrialConfig(0.25)),
        ("packed", ("mug", "bowl"), 8, "hsq", _TrialConfig(0.25)),
    ]
    with pytest.raises(ValueError, match="unknown planner"):
        backend.check(("hsq", "no-such-planner"))


def test_sim_backend_pickles_without_its_cache(tmp_path, monkeypatch) -> None:
    import pickle

    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", _trial_module([]))
    path = tmp_path / "trial.yaml"
    path.write_text("settle_s: 0.25\n")
    backend = SimBackend(str(path))
    backend.check(("hsq",))
    clone = pickle.loads(pickle.dumps(backend))
    assert clone.trial_config == str(path) and clone._config is None


def test_missing_or_incomplete_trial_runner(monkeypatch) -> None:
    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", None)
    with pytest.raises(TrialRunnerUnavailable, match="not available"):
        SimBackend().check(("hsq",))
    half = types.ModuleType("hsqbench.sim.trial")
    half.TrialConfig = _TrialConfig
    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", half)
    with pytest.raises(TrialRunnerUnavailable, match="run_isolated_trial"):
        SimBackend().check(("hsq",))


def test_fingerprint_is_the_resolved_tree_and_follows_every_named_config(tmp_path) -> None:
    """The fingerprint holds the resolved trial config tree: editing a config the trial config
    names (here the scene) changes it, and so the run's config hash; every planner's config,
    the oracle's and the object library's are in it, and the files named below config level
    (grippers, world files) too."""
    from hsqbench.settings import CONFIG_DIR

    scene = tmp_path / "scene.yaml"
    text = (CONFIG_DIR / "scene.yaml").read_text()
    scene.write_text(text)
    trial = tmp_path / "trial.yaml"
    trial.write_text(f"scene: {scene}\n")
    before = SimBackend(str(trial)).fingerprint()
    tree = before["trial_config"]
    assert {"scene", "robot", "physics", "perception", "graspability", "assets"} <= set(tree)
    assert set(tree["planners"]) == {"hsq", "baselines", "oracle", "contact_graspnet"}
    assert tree["planners"]["hsq"]["grasp"]["gripper"] in before["named_inputs"]["grippers"]
    assert before["named_inputs"]["scene_world"]
    assert SimBackend(str(trial)).fingerprint() == before
    scene.write_text(text.replace("margin_m: 0.02 ", "margin_m: 0.03 "))
    after = SimBackend(str(trial)).fingerprint()
    assert after["trial_config"]["scene"] != before["trial_config"]["scene"]
    assert after["trial_config"]["robot"] == before["trial_config"]["robot"]


def test_overrides_reach_into_named_configs_and_change_the_fingerprint() -> None:
    """Overrides (dotted paths into the tree's data) apply before the dataclasses are built, in
    any named file; a path that is not in the tree is an error naming it."""
    from hsqbench.errors import ConfigError

    base = SimBackend("trial").fingerprint()
    friction = base["trial_config"]["physics"]["objects"]["friction"]
    moved = SimBackend("trial", overrides=(("physics.objects.condim", 6),))
    assert moved.fingerprint()["trial_config"]["physics"]["objects"]["condim"] == 6
    assert moved.fingerprint()["trial_config"]["physics"]["objects"]["friction"] == friction
    assert moved.fingerprint() != base
    assert pickle.loads(pickle.dumps(moved)).fingerprint() == moved.fingerprint()
    with pytest.raises(ConfigError, match=r"'nothing' is not a key of physics.*valid keys"):
        SimBackend("trial", overrides=(("physics.nothing.here", 1),)).fingerprint()
    with pytest.raises(ConfigError, match=r"physics\.timestep_s holds .* which has no keys"):
        SimBackend("trial", overrides=(("physics.timestep_s.x", 1),)).fingerprint()


def test_presentation_groups_put_a_presentations_planners_together() -> None:
    """Consecutive specs that differ only in the planner form one group, in order; any other
    difference (pose index, seed, objects, experiment) starts a new one."""
    a, b = (TrialSpec("isolated", p, 0, 0, ("mug",), 11) for p in ("a", "b"))
    c = TrialSpec("isolated", "a", 0, 1, ("mug",), 12)
    d, e = (TrialSpec("packed", p, 0, 0, ("mug", "bowl"), 13) for p in ("a", "b"))
    f = TrialSpec("isolated", "b", 0, 0, ("mug",), 11)  # the first pose again, not adjacent
    assert presentation_groups([a, b, c, d, e, f]) == [[a, b], [c], [d, e], [f]]
    assert presentation_groups([]) == []
