"""How attempts end, as fractions per planner (hsqbench.experiment.plots.failures)."""

from __future__ import annotations

from collections import defaultdict

import numpy as np
import pytest

from hsqbench.experiment.plots.failures import OUTCOMES, draw_failures, outcome_fractions
from hsqbench.experiment.plots.palette import OUTCOME_COLOURS
from hsqbench.experiment.report import outcome_table
from tests.plot_runs import cut_off_texts, only, overlapping_texts, synthetic_run

PLANNERS = ("hsq", "antipodal", "oracle")


def _outcomes():
    table = outcome_table(synthetic_run())
    table.loc[0, "error"] = 2  # hsq isolated: two trials failed with an infrastructure error
    return table


def test_fractions_of_each_planners_attempts_sum_to_one():
    frac = outcome_fractions(_outcomes()).set_index(["experiment", "planner"])
    assert np.allclose(frac[list(OUTCOMES)].sum(axis=1), 1.0)
    anti = frac.loc[("isolated", "antipodal")]
    assert (anti["success"], anti["no_grasp_found"], anti["unreachable"]) == (0.4, 0.4, 0.1)
    assert frac.loc[("isolated", "hsq"), "errors"] == 2  # counted apart, not as attempts


def _bars(ax) -> dict[float, list]:
    by_row = defaultdict(list)
    for patch in ax.patches:
        by_row[round(patch.get_y() + patch.get_height() / 2, 6)].append(patch)
    return by_row


def test_each_planners_bar_fills_the_axis_in_outcome_colours():
    fig = draw_failures(_outcomes(), list(PLANNERS))
    assert [ax.get_title().split("\n")[0] for ax in fig.axes] == ["isolated", "packed"]
    assert "2 error trial(s) left out" in fig.axes[0].get_title()
    labels = [t.get_text() for t in fig.axes[0].get_yticklabels()]
    assert labels == ["hsq", "antipodal", "oracle (privileged)"]
    used = [o for o in OUTCOMES if outcome_fractions(_outcomes())[o].sum() > 0]
    for ax in fig.axes:
        rows = _bars(ax)
        assert sorted(rows) == [0.0, 1.0, 2.0]
        for patches in rows.values():
            assert len(patches) == len(used)
            assert sum(p.get_width() for p in patches) == pytest.approx(1.0)
    anti = sorted(_bars(fig.axes[0])[1.0], key=lambda p: p.get_x())
    widths = {OUTCOME_COLOURS[o]: p.get_width() for o, p in zip(used, anti, strict=True)}
    assert widths[OUTCOME_COLOURS["success"]] == pytest.approx(0.4)
    assert "40" in [t.get_text() for t in fig.axes[0].texts]  # the segment's percentage


def test_the_legend_sits_outside_the_bars_and_no_label_overlaps():
    fig = draw_failures(_outcomes(), list(PLANNERS))
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []
    renderer = fig.canvas.get_renderer()
    (legend,) = fig.legends
    box = legend.get_window_extent(renderer)
    assert not any(box.overlaps(ax.get_window_extent(renderer)) for ax in fig.axes)
    names = [t.get_text() for t in legend.get_texts()]
    assert names[0] == "success" and "no grasp found" in names


def test_nothing_to_draw_without_attempts():
    empty = _outcomes()
    empty["attempts"] = 0
    assert draw_failures(empty, list(PLANNERS)) is None


def test_one_experiment_makes_a_narrow_figure_whose_legend_still_fits():
    table = outcome_table(only(synthetic_run(pile=True), "pile"))
    fig = draw_failures(table, list(PLANNERS))
    assert [ax.get_title().split("\n")[0] for ax in fig.axes] == ["pile"]
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []
