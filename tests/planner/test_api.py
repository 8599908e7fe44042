"""The contract every planner shares (hsqbench.planner.api): the planning context's checks."""

from __future__ import annotations

import pytest

from hsqbench.planner.api import PlanningContext


def test_planning_context_normalises_and_checks_the_plane() -> None:
    ctx = PlanningContext(support_plane=(0.0, 0.0, 2.0, -0.2))
    assert ctx.support_plane == pytest.approx((0.0, 0.0, 1.0, -0.1))
    with pytest.raises(ValueError, match="zero"):
        PlanningContext(support_plane=(0.0, 0.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="4 finite"):
        PlanningContext(support_plane=(0.0, 1.0))
