"""A planner's own failure (hsqbench.planner.failure): an exception or output its contract rules
out becomes one line naming the plugin's file and line and the contract broken; ``hsqbench plan``
prints it and exits 2; the stop rule and VGN's count treat it as an attempt without a grasp."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hsqbench.cli import main
from hsqbench.experiment.clutter import vgn_round
from hsqbench.planner import registry
from hsqbench.planner.api import PlanningContext
from hsqbench.planner.failure import PlannerError, checked_plan
from hsqbench.planner.grasp import Grasp, InvalidGrasp
from hsqbench.sim.stop_rule import PackedConfig

#: A plugin file with one broken planner per way of breaking the contract; each ``# LINE name``
#: marks the line its error must name.
BROKEN = """
import numpy as np

from hsqbench.planner.api import PlanResult
from hsqbench.planner.base import PlannerBase
from hsqbench.planner.grasp import Grasp

DOWN = np.diag([1.0, -1.0, -1.0])


def _centre(clean):
    return clean.points.mean(axis=0)


class Raises(PlannerBase):
    name = "raises"

    def stages(self, clean, context):
        raise RuntimeError("the model file is missing")  # LINE raises


class NanPose(PlannerBase):
    name = "nan-pose"

    def stages(self, clean, context):
        position = _centre(clean) * np.nan
        return PlanResult(grasps=[Grasp(position, DOWN, 0.04, 1.0)])  # LINE nan-pose


class InfPose(PlannerBase):
    name = "inf-pose"

    def stages(self, clean, context):
        position = _centre(clean) + np.inf
        return PlanResult(grasps=[Grasp(position, DOWN, 0.04, 1.0)])  # LINE inf-pose


class Skewed(PlannerBase):
    name = "skewed"

    def stages(self, clean, context):
        return PlanResult(grasps=[Grasp(_centre(clean), 2 * DOWN, 0.04, 1.0)])  # LINE skewed


class NegativeWidth(PlannerBase):
    name = "negative-width"

    def stages(self, clean, context):
        return PlanResult(grasps=[Grasp(_centre(clean), DOWN, -0.01, 1.0)])  # LINE negative-width


class NanScore(PlannerBase):
    name = "nan-score"

    def stages(self, clean, context):  # LINE nan-score
        return PlanResult(grasps=[Grasp(_centre(clean), DOWN, 0.04, np.nan)])


class Listed(PlannerBase):
    name = "listed"

    def stages(self, clean, context):  # LINE listed
        return [Grasp(_centre(clean), DOWN, 0.04, 1.0)]


class Dicts(PlannerBase):
    name = "dicts"

    def stages(self, clean, context):  # LINE dicts
        return PlanResult(grasps=[{"position": _centre(clean)}])


class BadInit(PlannerBase):
    name = "bad-init"

    def __init__(self, config=None):
        raise OSError("weights.pt not found")  # LINE bad-init

    def stages(self, clean, context):
        return PlanResult(grasps=[])


class NoBase:
    name = "no-base"

    def plan(self, points, context):  # LINE no-base
        return None
"""

#: How each planner's one line says what contract it broke.
BROKE = {
    "raises": "raised RuntimeError",
    "nan-pose": "built an invalid Grasp",
    "inf-pose": "built an invalid Grasp",
    "skewed": "grasp rotation must be a proper rotation",
    "negative-width": "grasp width must be a finite length >= 0 m",
    "nan-score": "stages at {where} returned grasps[0] with score NaN",
    "listed": "stages at {where} returned list, not a PlanResult",
    "dicts": "returned grasps[0] as dict, not a Grasp",
    "no-base": "plan at {where} returned NoneType, not a PlanResult",
}
CLASSES = {
    "raises": "Raises",
    "nan-pose": "NanPose",
    "inf-pose": "InfPose",
    "skewed": "Skewed",
    "negative-width": "NegativeWidth",
    "nan-score": "NanScore",
    "listed": "Listed",
    "dicts": "Dicts",
    "no-base": "NoBase",
    "bad-init": "BadInit",
}


@pytest.fixture(autouse=True)
def _fresh_registry(monkeypatch):
    """Each test registers its plugins in a registry of its own."""
    monkeypatch.setattr(registry, "_SPECS", {})
    monkeypatch.setattr(registry, "_FACTORIES", dict(registry._FACTORIES))


@pytest.fixture
def broken(tmp_path: Path) -> Path:
    path = tmp_path / "broken.py"
    path.write_text(BROKEN)
    return path


def line_of(path: Path, name: str) -> str:
    """``path:line`` of the line marked ``# LINE name``."""
    lines = path.read_text().splitlines()
    number = next(i + 1 for i, text in enumerate(lines) if text.endswith(f"# LINE {name}"))
    return f"{path}:{number}"


def _cloud() -> np.ndarray:
    rng = np.random.default_rng(0)
    return rng.uniform([-0.03, -0.02, 0.0], [0.03, 0.02, 0.06], (1500, 3)) + np.array([0.5, 0, 0])


@pytest.mark.parametrize("name", list(BROKE))
def test_each_broken_contract_is_one_line_naming_the_plugins_line(broken, name):
    planner = registry.get_planner(registry.resolve_planner(f"{broken}:{CLASSES[name]}"))
    with pytest.raises(PlannerError) as caught:
        checked_plan(planner, _cloud(), PlanningContext(support_plane=(0.0, 0.0, 1.0, 0.0)))
    message, where = str(caught.value), line_of(broken, name)
    assert "\n" not in message and message.startswith(f"planner {name!r}")
    assert where in message, message
    assert BROKE[name].format(where=where) in message
    assert "grasp.py" not in message and "docs/your-own-planner.md" in message


def test_a_plugin_that_cannot_be_built_names_its_line(broken, tmp_path, capsys):
    name = registry.resolve_planner(f"{broken}:BadInit")
    with pytest.raises(ValueError) as caught:
        registry.get_planner(name)
    message = str(caught.value)
    assert message.startswith("planner ") and "cannot be built: OSError at " in message
    assert line_of(broken, "bad-init") in message and "weights.pt not found" in message
    cloud = tmp_path / "cloud.npy"
    np.save(cloud, _cloud())
    assert main(["plan", str(cloud), "--planner", f"{broken}:BadInit"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and line_of(broken, "bad-init") in err


def test_an_invalid_grasp_is_a_value_error_of_its_own():
    with pytest.raises(InvalidGrasp, match="must be finite"):
        Grasp(np.full(3, np.nan), np.eye(3), 0.02, 1.0)
    with pytest.raises(InvalidGrasp, match="a position of 3 numbers"):
        Grasp(np.zeros(4), np.eye(3), 0.02, 1.0)
    assert issubclass(InvalidGrasp, ValueError)  # callers that caught ValueError still do


def test_plan_prints_one_line_and_exits_2_for_a_plugin_that_raises(broken, tmp_path, capsys):
    cloud = tmp_path / "cloud.npy"
    np.save(cloud, _cloud())
    for name in ("raises", "listed", "nan-pose"):
        code = main(["plan", str(cloud), "--planner", f"{broken}:{CLASSES[name]}"])
        err = capsys.readouterr().err
        assert code == 2
        assert err.count("\n") == 1 and "Traceback" not in err
        assert err.startswith("hsqbench plan: error: planner") and line_of(broken, name) in err


def test_a_planner_error_is_a_failure_for_the_stop_rule_and_no_grasp_for_vgns():
    rule = PackedConfig()
    assert "consecutive failures" in rule.stop_reason(["planner_error"] * 2, objects_left=True)
    assert rule.stop_reason(["success", "planner_error"], objects_left=True) is None
    vgn = PackedConfig(stop_on_no_grasp=True)
    assert "no grasp" in vgn.stop_reason(["success", "planner_error"], objects_left=True)
    # VGN's count ends the round before the first attempt without a grasp, as for no_grasp_found.
    assert vgn_round(["success", "planner_error", "success"], [True, False, True]) == (1, 1, True)


def test_numpy_timings_are_seconds_too():
    class Timed:
        name = "timed"

        def plan(self, points, context):
            from hsqbench.planner.api import PlanResult

            return PlanResult(grasps=[], timings={"net": np.float32(0.5)}, reason="none")

    assert checked_plan(Timed(), _cloud(), PlanningContext()).timings["net"] == 0.5
