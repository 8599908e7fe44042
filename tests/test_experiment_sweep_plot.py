"""A sweep parameter's figure (hsqbench.experiment.sweep_plot)."""

from __future__ import annotations

import pandas as pd

from hsqbench.experiment.plots.palette import FIXED
from hsqbench.experiment.sweep_plot import draw_parameter

PARAM = {
    "axis": "cameras",
    "categorical": True,
    "points": [{"label": "both", "x": None}, {"label": "left", "x": None}],
}


def _rows(protocol: str, planners: list[str]) -> list[dict]:
    return [
        {
            "protocol": protocol,
            "experiment": "isolated",
            "planner": planner,
            "point": point,
            "n": 10,
            "gsr_percent": 50.0 + point,
            "gsr_ci_low_percent": 40.0,
            "gsr_ci_high_percent": 60.0,
            "confidence": 0.95,
        }
        for planner in planners
        for point in (0, 1)
    ]


def test_a_planner_keeps_its_colour_in_every_panel():
    # The second protocol ran fewer planners: colours must not follow each panel's own order.
    rows = pd.DataFrame(
        _rows("paper", ["hsq", "single-sq", "antipodal"]) + _rows("ycb", ["hsq", "antipodal"])
    )
    fig = draw_parameter(rows, PARAM)
    panels = [{line.get_label(): line.get_color() for line in ax.get_lines()} for ax in fig.axes]
    assert [set(p) for p in panels] == [{"hsq", "single-sq", "antipodal"}, {"hsq", "antipodal"}]
    assert panels[1] == {k: v for k, v in panels[0].items() if k in panels[1]}
    assert len(set(panels[0].values())) == 3
    # ... and the colour it has in a run's report (one palette for every figure).
    assert panels[0] == {p: FIXED[p] for p in ("hsq", "single-sq", "antipodal")}
