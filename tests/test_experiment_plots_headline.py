"""The headline figure: GSR and CR per planner with intervals, all and graspable presentations,
reported rows hollow (hsqbench.experiment.plots.headline)."""

from __future__ import annotations

import pytest

from hsqbench.experiment.plots.headline import draw_headline, measured_rates
from hsqbench.experiment.plots.palette import FIXED
from hsqbench.experiment.reported import reported_rows
from hsqbench.experiment.stats import wilson_interval
from tests.plot_runs import cut_off_texts, only, overlapping_texts, synthetic_run

LONG = ("hsq-no-support-facing", "contact-graspnet-elim", "oracle")


def _bar(ax, label: str) -> tuple[float, float, float, float]:
    """(x, y, low, high) of the interval drawn with ``label`` in ``ax``."""
    (container,) = [c for c in ax.containers if c.get_label() == label]
    line, _, (bars,) = container.lines
    (low, _), (high, _) = bars.get_segments()[0]
    return float(line.get_xdata()[0]), float(line.get_ydata()[0]), low, high


def test_rates_are_the_counts_with_wilson_intervals():
    rates = measured_rates(synthetic_run()).set_index(["experiment", "rate", "planner", "scope"])
    iso = rates.loc[("isolated", "gsr", "antipodal", "all")]
    low, high = wilson_interval(4, 10)
    assert (iso["n"], iso["percent"]) == (10, 40.0)
    assert iso["low"] == pytest.approx(100 * low) and iso["high"] == pytest.approx(100 * high)
    assert rates.loc[("isolated", "gsr", "antipodal", "graspable"), "percent"] == 50.0
    assert rates.loc[("packed", "cr", "hsq", "all"), "percent"] == 90.0  # 9 of 10 objects
    assert rates.loc[("packed", "cr", "hsq", "graspable"), "n"] == 8  # 4 graspable a round
    assert "pile" not in set(rates.index.get_level_values(0))


def test_panels_rows_and_intervals():
    fig = draw_headline(synthetic_run())
    axes = [ax for ax in fig.axes if ax.get_visible()]
    titles = [ax.get_title().split("\n") for ax in axes]
    assert [t[0] for t in titles] == ["isolated GSR", "packed GSR", "packed CR"]
    assert titles[0][1] == "n = 10 attempts, 8 graspable"
    labels = [t.get_text() for t in axes[0].get_yticklabels()]
    reported = [
        f"{r.method}, reported" for r in (*reported_rows("isolated"), *reported_rows("packed"))
    ]
    assert labels == ["hsq", "antipodal", "oracle (privileged)", *dict.fromkeys(reported)]
    x, y, low, high = _bar(axes[0], "antipodal (all)")
    lo, hi = wilson_interval(4, 10)
    assert (x, low, high) == pytest.approx((40.0, 100 * lo, 100 * hi))
    gx, gy, _, _ = _bar(axes[0], "antipodal (graspable)")
    assert gx == 50.0 and round(y) == round(gy) == 1 and y != gy  # one row, side by side
    for ax in axes:
        assert ax.containers[0].lines[0].get_color() == FIXED["hsq"]


def test_reported_rows_are_hollow_and_at_the_papers_numbers():
    fig = draw_headline(synthetic_run())
    for ax, experiment in zip(fig.axes, ("isolated", "packed"), strict=False):
        (hollow,) = [line for line in ax.get_lines() if line.get_label() == "reported"]
        assert hollow.get_markerfacecolor() == "none"
        expected = sorted(r.gsr_percent for r in reported_rows(experiment))
        assert sorted(hollow.get_xdata()) == expected
    without = draw_headline(synthetic_run(), with_reported=False)
    assert all("reported" not in t.get_text() for t in without.axes[0].get_yticklabels())


def test_piles_add_two_panels_on_a_second_row():
    fig = draw_headline(synthetic_run(pile=True))
    shown = [ax.get_title().split("\n")[0] for ax in fig.axes if ax.get_visible()]
    assert shown == ["isolated GSR", "packed GSR", "packed CR", "pile GSR", "pile CR"]
    assert len(fig.axes) == 6 and not fig.axes[5].get_visible()


def test_long_planner_names_overlap_nothing():
    data = synthetic_run()
    renamed = dict(zip(("hsq", "antipodal", "oracle"), LONG, strict=True))
    data.attempts["planner"] = data.attempts["planner"].map(renamed)
    data.rounds["planner"] = data.rounds["planner"].map(renamed)
    data.planners = list(LONG)
    fig = draw_headline(data)
    assert overlapping_texts(fig) == []
    assert cut_off_texts(fig) == []


def test_nothing_to_draw_without_measured_rows():
    data = synthetic_run()
    data.attempts = data.attempts[:0]
    data.rounds = data.rounds[:0]
    assert draw_headline(data) is None


@pytest.mark.parametrize("experiment", ["isolated", "pile"])
def test_one_experiment_makes_a_narrow_figure_whose_legend_still_fits(experiment):
    fig = draw_headline(only(synthetic_run(pile=True), experiment))
    assert len(fig.axes) == (1 if experiment == "isolated" else 2)
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []
