"""GSR per object as a heat map, and planning time (hsqbench.experiment.plots.per_object)."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import to_rgb

from hsqbench.experiment.plots.palette import FIXED
from hsqbench.experiment.plots.per_object import draw_gsr_per_object, draw_planning_time
from hsqbench.experiment.report import table1_per_object
from tests.plot_runs import cut_off_texts, overlapping_texts, synthetic_run


def test_a_cell_per_object_and_planner_holding_its_gsr():
    data = synthetic_run(planners=("oracle", "hsq", "antipodal"))
    t1o = table1_per_object(data)
    fig = draw_gsr_per_object(data, t1o)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["hsq", "antipodal", "oracle"]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["mug", "bowl"]
    assert ax.get_xticklabels()[0].get_color() == FIXED["hsq"]
    grid = np.asarray(ax.images[0].get_array())
    expected = t1o.pivot_table(index="object", columns="planner", values="gsr_percent")
    assert np.allclose(grid, expected.loc[["mug", "bowl"], ["hsq", "antipodal", "oracle"]])
    assert sorted(t.get_text() for t in ax.texts) == sorted(f"{v:.0f}" for v in grid.ravel())
    assert ax.get_title().endswith("n = 5 attempts per cell")
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []


def test_forty_objects_still_fit_their_labels():
    data = synthetic_run()
    names = [f"object_with_a_long_name_{k:02d}" for k in range(40)]
    data.attempts = data.attempts.loc[data.attempts.index.repeat(4)].reset_index(drop=True)
    iso = data.attempts["experiment"] == "isolated"
    data.attempts.loc[iso, "objects"] = [names[k % 40] for k in range(int(iso.sum()))]
    data.objects = names
    fig = draw_gsr_per_object(data, table1_per_object(data))
    assert len(fig.axes[0].get_yticklabels()) == 40
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []


def test_planning_time_has_a_box_per_planner_in_its_colour():
    fig = draw_planning_time(synthetic_run())
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["hsq", "antipodal", "oracle"]
    boxes = list(ax.patches)
    assert len(boxes) == 3
    assert to_rgb(boxes[1].get_facecolor()) == to_rgb(FIXED["antipodal"])
