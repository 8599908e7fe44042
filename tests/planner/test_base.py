"""The one front door of the cloud planners (hsqbench.planner.base)."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
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
