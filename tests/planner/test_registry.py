"""Planner names: optional planners whose extra is missing are named with the fix."""

from __future__ import annotations

import numpy as np
import pytest

import hsqbench.planner.learned.network as network
from hsqbench.experiment.backend import SimBackend
from hsqbench.planner.api import Planner, PlanningContext, PlanResult
from hsqbench.planner.hsq.planner import HSQPlanner
from hsqbench.planner.registry import (
    PRIVILEGED,
    get_planner,
    planner_names,
    register_planner,
    runnable,
    unavailable,
)


def test_builtin_planners_are_registered_and_the_oracle_is_privileged():
    names = set(planner_names())
    assert {"hsq", "single-sq", "antipodal", "oracle", "contact-graspnet"} <= names
    assert names >= PRIVILEGED and "hsq" not in PRIVILEGED


def test_a_missing_extra_is_reported_with_the_install_commands(monkeypatch):
    monkeypatch.setattr(network, "available", lambda: False)
    assert "make learned" in unavailable("contact-graspnet")
    assert "make learned" in unavailable("contact-graspnet-elim")
    assert unavailable("hsq") is None and unavailable("oracle") is None
    with pytest.raises(ValueError, match=r"'contact-graspnet' cannot run: .*pip install"):
        SimBackend().check(("hsq", "contact-graspnet"))


def test_with_the_extra_nothing_is_reported(monkeypatch):
    monkeypatch.setattr(network, "available", lambda: True)
    assert unavailable("contact-graspnet") is None


def test_runnable_leaves_out_planners_without_their_extra_and_says_why(monkeypatch, capsys):
    monkeypatch.setattr(network, "available", lambda: False)
    assert runnable(["hsq", "contact-graspnet", "antipodal"]) == ["hsq", "antipodal"]
    assert "leaving out planner contact-graspnet" in capsys.readouterr().err
    monkeypatch.setattr(network, "available", lambda: True)
    assert runnable(["hsq", "contact-graspnet"]) == ["hsq", "contact-graspnet"]


def test_registry_builds_planners_by_name() -> None:
    assert "hsq" in planner_names()
    planner = get_planner("hsq")
    assert isinstance(planner, HSQPlanner) and isinstance(planner, Planner)
    with pytest.raises(ValueError, match=r"choose one of: .*hsq"):
        get_planner("no-such-planner")

    class Nothing:
        name = "nothing"

        def plan(self, points, context) -> PlanResult:
            return PlanResult(grasps=[], reason="never plans", planner=self.name)

    register_planner("test-nothing", lambda config=None: Nothing(), replace=True)
    assert get_planner("test-nothing").plan(np.zeros((5, 3)), PlanningContext()).reason
    with pytest.raises(ValueError, match="already registered"):
        register_planner("test-nothing", lambda config=None: Nothing())
