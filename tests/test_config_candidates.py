"""configs/candidates/: the settings judged for issue 42 (docs/performance.md). Each protocol
there is its base protocol with one physics value changed, so `hsqbench compare` against a run
of the base protocol pairs the same trials and isolates that value."""

from __future__ import annotations

from pathlib import Path

import pytest

from hsqbench.config import load_tree, to_dict
from hsqbench.experiment.config import load_experiment_config
from hsqbench.sim.trial import TrialConfig

CANDIDATES = Path(__file__).resolve().parents[1] / "configs" / "candidates"
PROTOCOLS = sorted(p for p in CANDIDATES.glob("*.yaml") if p.stem.startswith(("paper3_", "ycb3_")))


def test_there_are_candidates():
    assert len(PROTOCOLS) >= 3


@pytest.mark.parametrize("path", PROTOCOLS, ids=lambda p: p.stem)
def test_a_candidate_changes_one_physics_value_of_its_base(path, monkeypatch):
    monkeypatch.chdir(CANDIDATES.parents[1])  # trial_config paths are repository-relative
    candidate = load_experiment_config(path)
    base = load_experiment_config(path.stem.split("_")[0])
    assert to_dict(candidate) | {"trial_config": base.trial_config} == to_dict(base)
    new = to_dict(load_tree(TrialConfig, candidate.trial_config))
    old = to_dict(load_tree(TrialConfig, base.trial_config))
    assert [k for k in old if old[k] != new[k]] == ["physics"]
    changed = [k for k in old["physics"] if old["physics"][k] != new["physics"][k]]
    assert len(changed) == 1
