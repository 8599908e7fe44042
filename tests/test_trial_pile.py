"""Pile rounds (run_packed_round(kind="pile")): the packed stop rule on a pile scene, and the
VGN/GIGA switch that ends a round at the first attempt without a grasp."""

from __future__ import annotations

from dataclasses import replace

import pytest

from hsqbench.planner.api import PlanResult
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.robot import load_robot_config, menagerie_path
from hsqbench.sim.stop_rule import PackedConfig
from hsqbench.sim.trial import load_trial_config, run_packed_round

try:
    menagerie_path(load_robot_config())
except FileNotFoundError as exc:  # pragma: no cover - depends on the machine
    pytest.skip(f"Menagerie not available: {exc}", allow_module_level=True)

OBJECTS = ["proc_box", "proc_cylinder", "proc_l"]


class NoGrasp:
    name = "none"

    def plan(self, points, context) -> PlanResult:
        assert context.packed  # pile rounds plan as packed ones (no h_delta)
        return PlanResult(grasps=[], reason="nothing fits", planner=self.name)


@pytest.fixture(scope="module")
def config():
    return replace(load_trial_config(), sensor="surface")


def test_a_pile_round_uses_the_packed_rule_on_a_pile(config):
    result = run_packed_round(OBJECTS, 5, NoGrasp(), config, kind="pile")
    assert [a.outcome for a in result.attempts] == [Outcome.NO_GRASP_FOUND] * 2
    assert result.objects == OBJECTS and result.objects_cleared == []


def test_stop_on_no_grasp_ends_a_pile_round_at_once_and_leaves_packed_rounds_alone(config):
    vgn = replace(config, pile=PackedConfig(stop_on_no_grasp=True))
    pile = run_packed_round(OBJECTS, 5, NoGrasp(), vgn, kind="pile")
    assert [a.outcome for a in pile.attempts] == [Outcome.NO_GRASP_FOUND]
    packed = run_packed_round(OBJECTS, 5, NoGrasp(), vgn)
    assert len(packed.attempts) == 2


def test_unknown_round_kind_is_an_error(config):
    with pytest.raises(ValueError, match="packed or pile"):
        run_packed_round(OBJECTS, 5, NoGrasp(), config, kind="isolated")
