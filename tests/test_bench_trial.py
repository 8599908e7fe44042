"""bench/bench_trial.py's ``--set``: a candidate trial-config value priced against a reference
version (issue 42), checked before any worker starts and never handed to the reference."""

from __future__ import annotations

import pytest

from bench.bench_trial import parse_overrides
from bench.trial_compare import version_requests


def test_values_are_read_as_yaml():
    assert parse_overrides(["physics.timestep_s=0.004", "ik.restarts=4"]) == {
        "physics.timestep_s": 0.004,
        "ik.restarts": 4,
    }
    assert parse_overrides([]) == {}


def test_a_malformed_item_names_the_form_to_write():
    with pytest.raises(SystemExit, match="write KEY=VALUE"):
        parse_overrides(["physics.timestep_s"])


def test_an_unknown_key_fails_before_any_worker_starts():
    with pytest.raises(SystemExit, match="timestep_ms"):
        parse_overrides(["physics.timestep_ms=0.004"])


def test_a_value_the_config_rejects_fails_too():
    with pytest.raises(SystemExit, match="restarts"):
        parse_overrides(["ik.restarts=0"])


def test_the_reference_runs_without_the_candidate_setting():
    group = {"name": "mug/0", "trial_config": "trial", "specs": [], "overrides": {"ik.restarts": 4}}
    requests = version_requests(group)
    assert requests["new"]["overrides"] == {"ik.restarts": 4}
    assert "overrides" not in requests["reference"]
    assert requests["reference"]["specs"] is group["specs"]
