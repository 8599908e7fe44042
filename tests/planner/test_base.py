"""The one front door of the cloud planners (hsqbench.planner.base)."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.base import PlannerBase
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.hsq.planner import HSQPlanner, plan_grasps


def test_every_cloud_planner_goes_through_the_one_front_door() -> None:
    """hsq and the baselines share PlannerBase's plan (validate, clean, time, assemble) and
    supply only their stages; the function forms take the context's keywords; a cloud that
    cleaning empties gets the same answer from each, under its own name."""
    import inspect

    from hsqbench.planner.base import PlannerBase
    from hsqbench.planner.baselines.antipodal import AntipodalPlanner, plan_antipodal
    from hsqbench.planner.baselines.single_sq import SingleSQPlanner, plan_single_sq

    for cls in (HSQPlanner, SingleSQPlanner, AntipodalPlanner):
        assert issubclass(cls, PlannerBase) and "plan" not in vars(cls), cls.__name__
    keywords = {"packed", "support_plane", "seed", "camera_positions"}
    for fn in (plan_grasps, plan_single_sq, plan_antipodal):
        assert keywords <= set(inspect.signature(fn).parameters), fn.__name__
    scattered = np.arange(15, dtype=float).reshape(5, 3)  # five points metres apart: outliers
    context = PlanningContext(support_plane=(0, 0, 1, 0), seed=3)
    results = [
        cls().plan(scattered, context) for cls in (HSQPlanner, SingleSQPlanner, AntipodalPlanner)
    ]
    assert [r.planner for r in results] == ["hsq", "single-sq", "antipodal"]
    for r in results:
        assert not r.grasps and r.n_removed == 5 and list(r.timings) == ["cleaning", "total"]
        assert r.reason == results[0].reason and r.reason
    with pytest.raises(ValueError, match="NaN"):
        SingleSQPlanner().plan(np.full((4, 3), np.nan), context)


# ----------------------------------------------------------------------------- the contract
def _cube_cloud() -> np.ndarray:
    """The six faces of a 4 cm cube standing on the table at (0.5, 0, 0)."""
    u = np.random.default_rng(0).uniform(-0.02, 0.02, (3000, 2))
    faces = [np.insert(u, axis, sign * 0.02, axis=1) for axis in range(3) for sign in (-1, 1)]
    return np.concatenate(faces) + np.array([0.5, 0.0, 0.02])


def _top_down(closing, width: float, score: float) -> Grasp:
    closing, down = np.asarray(closing, dtype=float), np.array([0.0, 0.0, -1.0])
    rotation = np.column_stack([closing, np.cross(down, closing), down])
    return Grasp(np.array([0.5, 0.0, 0.02]), rotation, width, score)


class _Proposes(PlannerBase):
    """Proposes the given grasps through the harness's rules."""

    name = "proposes"

    def __init__(self, grasps: list[Grasp]) -> None:
        self.grasps = grasps

    def stages(self, clean, context):
        return self.apply_rules(self.grasps, clean, context)


def test_a_planner_that_opts_into_the_rules_loses_what_they_remove_and_is_ranked() -> None:
    wide = _top_down([1, 0, 0], 0.2, 1.0)  # wider than the hand opens
    planner = _Proposes([_top_down([1, 0, 0], 0.04, 0.5), _top_down([0, 1, 0], 0.04, 0.9), wide])
    result = planner.plan(_cube_cloud(), PlanningContext(support_plane=(0, 0, 1, 0)))
    assert [g.score for g in result.grasps] == [0.9, 0.5]
    assert result.removed_by["width"] == 1 and result.remaining["synthesised"] == 3
    assert list(result.timings) == ["cleaning", "elimination", "total"]

    alone = _Proposes([wide]).plan(_cube_cloud(), PlanningContext(support_plane=(0, 0, 1, 0)))
    assert len(alone.grasps) == 0
    assert alone.reason.startswith("no grasp survived: of 1 grasps, the rules removed width 1")


def test_the_contract_names_a_missing_stage_and_cleans_as_hsq_by_default() -> None:
    class NoStages(PlannerBase):
        name = "no-stages"

    with pytest.raises(TypeError, match=r"abstract method '?stages"):
        NoStages()
    assert _Proposes([]).cleaning_config() == HSQPlanner().config.cleaning
