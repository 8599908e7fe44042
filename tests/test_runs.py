"""The Python API's checks and helpers (the runs themselves: tests/test_examples.py runs
examples/notebook_api.py through the simulator)."""

from __future__ import annotations

from pathlib import Path

import pytest

import hsqbench
from hsqbench.experiment.config import load_experiment_config
from hsqbench.planner.base import PlannerBase
from hsqbench.runs import protocol_planners, run_folder
from hsqbench.settings import RESULTS_DIR


class _Here(PlannerBase):
    """A planner defined in this process (as in a notebook cell)."""

    name = "here"

    def stages(self, clean, context):
        raise AssertionError("not planned in these tests")


def test_the_package_exports_the_api():
    assert hsqbench.run_trial is hsqbench.runs.run_trial
    assert {"run_trial", "run_benchmark", "load_run"} <= set(hsqbench.__all__)


def test_a_planner_of_this_process_cannot_go_to_workers():
    with pytest.raises(ValueError, match=r"jobs=1, or put it in a file .*file\.py:ClassName"):
        hsqbench.run_benchmark("quick", planners=[_Here], jobs=2)


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: hsqbench.run_benchmark("quik"), r"no protocol 'quik' \(did you mean 'quick'\?\)"),
        (lambda: hsqbench.run_trial("proc_cylindr"), r"did you mean 'proc_cylinder'"),
        (lambda: hsqbench.run_trial("proc_box", scene="heap"), r"scene must be one of"),
        (lambda: hsqbench.run_trial(scene="packed", objects=["proc_box"], planner="hqs"), "'hsq'"),
    ],
)
def test_bad_input_is_one_clear_error_before_anything_runs(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_planners_the_protocol_lacks_join_its_list_and_a_subset_keeps_it():
    quick = load_experiment_config("quick")
    same, chosen = protocol_planners(quick, ["hsq"])
    assert same == quick and chosen == ["hsq"]
    joined, chosen = protocol_planners(quick, ["antipodal", "hsq"])
    assert joined.planners == (*quick.planners, "antipodal") and chosen == ["antipodal", "hsq"]


def test_run_folders_are_named_or_dated():
    assert run_folder("mine", "quick") == RESULTS_DIR / "mine"
    assert run_folder("some/where", "quick") == Path("some/where")
    assert run_folder(None, "configs/protocols/quick.yaml").name.startswith("quick-")
