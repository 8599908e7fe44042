"""The packed stop rule (hsqbench.sim.stop_rule), shared by the runner, fake backend, report."""

from __future__ import annotations

import pytest

from hsqbench.sim.stop_rule import PackedConfig

F, S, U = "empty_grasp", "success", "sim_unstable"


def test_the_rule_stops_for_each_of_its_reasons_and_only_then() -> None:
    rule = PackedConfig(max_consecutive_failures=2, max_attempts=5)
    assert rule.stop_reason([], objects_left=True) is None
    assert rule.stop_reason([S, F], objects_left=True) is None
    assert rule.stop_reason([F, S, F], objects_left=True) is None
    assert "consecutive" in rule.stop_reason([S, F, F], objects_left=True)
    assert "clear" in rule.stop_reason([S, S], objects_left=False)
    assert "unstable" in rule.stop_reason([S, U], objects_left=True)
    assert "cap" in rule.stop_reason([S, F, S, F, S], objects_left=True)


def test_ended_early_accepts_the_cap_and_instability() -> None:
    rule = PackedConfig(max_consecutive_failures=2, max_attempts=3)
    assert rule.ended_early([S, F], objects_left=True)
    assert not rule.ended_early([S, F, S], objects_left=True)  # the attempt cap
    assert not rule.ended_early([S, U], objects_left=True)
    assert not rule.ended_early([S], objects_left=False)
    assert PackedConfig(max_consecutive_failures=3).ended_early([S, F, F], objects_left=True)


def test_bad_settings_are_errors() -> None:
    with pytest.raises(ValueError, match="max_consecutive_failures"):
        PackedConfig(max_consecutive_failures=0)


def test_stop_on_no_grasp_ends_a_round_at_the_first_attempt_without_a_grasp() -> None:
    vgn = PackedConfig(stop_on_no_grasp=True)
    assert "no grasp" in vgn.stop_reason(["success", "no_grasp_found"], objects_left=True)
    assert vgn.stop_reason(["no_grasp_found", "success"], objects_left=True) is None
    # the paper's rule counts it as one failure of two
    assert PackedConfig().stop_reason(["success", "no_grasp_found"], objects_left=True) is None
