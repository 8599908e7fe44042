"""One colour per planner across figures (hsqbench.experiment.plots.palette)."""

from __future__ import annotations

from hsqbench.experiment.plots.palette import FIXED, OUTCOME_COLOURS, SPARE, planner_colours
from hsqbench.sim.outcome import Outcome


def test_shipped_planners_keep_their_colour_whatever_else_is_drawn():
    alone = planner_colours(["antipodal"])
    crowded = planner_colours(["hsq-no-caps", "oracle", "antipodal", "my-planner", "hsq"])
    assert alone["antipodal"] == crowded["antipodal"] == FIXED["antipodal"]
    assert crowded["hsq"] == FIXED["hsq"] and crowded["oracle"] == FIXED["oracle"]


def test_other_planners_take_distinct_spare_colours_in_the_order_given():
    names = [f"hsq-no-{k}" for k in range(len(SPARE))]
    colours = planner_colours(["hsq", *names])
    assert [colours[n] for n in names] == list(SPARE)
    assert len(set(colours.values())) == len(colours)
    assert not set(SPARE) & set(FIXED.values())


def test_every_outcome_and_errors_have_a_colour():
    assert set(OUTCOME_COLOURS) == {str(o) for o in Outcome} | {"error"}
    assert len(set(OUTCOME_COLOURS.values())) == len(OUTCOME_COLOURS)
