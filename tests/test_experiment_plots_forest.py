"""The paired comparison as a forest plot (hsqbench.experiment.plots.forest)."""

from __future__ import annotations

import pandas as pd
import pytest

from hsqbench.experiment.paired_table import paired_table
from hsqbench.experiment.plots.forest import draw_forest, right_label
from hsqbench.experiment.plots.palette import FIXED
from tests.plot_runs import cut_off_texts, overlapping_texts, synthetic_run

PLANNERS = ["hsq", "antipodal", "oracle"]


def _paired() -> pd.DataFrame:
    table = paired_table(synthetic_run(), "hsq")
    # An interval over objects as a run with enough objects has (two are too few for one).
    table.loc[0, ["ci_low_pp", "ci_high_pp"]] = (-80.0, -5.0)
    return table


def _interval(ax, label: str) -> tuple[float, float, float]:
    """(low, high, y) of the interval drawn with ``label``."""
    (container,) = [c for c in ax.containers if c.get_label() == label]
    (bars,) = container.lines[2]
    (low, y), (high, _) = bars.get_segments()[0]
    return low, high, y


def test_a_panel_per_comparison_a_row_per_planner_the_reference_at_zero():
    table = _paired()
    fig = draw_forest(table, PLANNERS, 0.95)
    axes = fig.axes[0::2]  # plots, each with its column of numbers beside it
    assert [ax.get_title().split(":")[0] for ax in axes] == [
        "isolated GSR",
        "packed CR",
        "packed GSR",
    ]
    assert axes[0].get_title() == "isolated GSR: planner − hsq, over 2 objects"
    for ax in axes:
        assert [t.get_text() for t in ax.get_yticklabels()] == ["antipodal", "oracle (privileged)"]
        lo, hi = ax.get_xlim()
        assert lo < 0 < hi
        assert any(tuple(line.get_xdata()) == (0, 0) for line in ax.get_lines())
    row = table.iloc[0]  # antipodal, isolated GSR
    low, high, y = _interval(axes[0], "antipodal (clusters)")
    (marker,) = [c for c in axes[0].containers if c.get_label() == "antipodal (clusters)"]
    assert marker.lines[0].get_xdata()[0] == pytest.approx(row["difference_pp"])
    assert (low, high) == (-80.0, -5.0)
    p_low, p_high, p_y = _interval(axes[0], "antipodal (presentations)")
    assert (p_low, p_high) == pytest.approx(
        (row["presentations_ci_low_pp"], row["presentations_ci_high_pp"])
    )
    assert p_y > y  # drawn just below the one over objects
    assert axes[0].get_xlim()[0] < -80.0  # every bound in view
    assert axes[0].containers[0].lines[0].get_color() == FIXED["antipodal"]
    # Two rounds are too few for a bootstrap and CR has no test over objects: points only.
    markers = [c for c in axes[1].containers]
    assert [c.get_label() for c in markers] == ["antipodal (clusters)", "oracle (clusters)"]
    assert all(not c.has_xerr for c in markers)


def test_the_right_margin_gives_numbers_and_the_verdict():
    table = _paired()
    fig = draw_forest(table, PLANNERS, 0.95)
    numbers = fig.axes[1]  # the column beside the isolated panel
    texts = [t.get_text() for t in numbers.texts]
    isolated = table[table["comparison"] == "isolated GSR"]
    assert texts == [right_label(r) for _, r in isolated.iterrows()]
    row = isolated.iloc[0]
    assert texts[0].startswith(f"{row['difference_pp']:+.1f} [")
    assert texts[0].endswith(str(row["verdict"]))
    assert f"{int(row['only_planner'])}:{int(row['only_reference'])}" in texts[0]
    assert overlapping_texts(fig) == [] and cut_off_texts(fig) == []


def test_tiny_p_values_read_as_a_bound():
    row = _paired().iloc[0].copy()
    row["p_holm"] = 3e-12
    assert "p<0.001" in right_label(row)
    row["p_holm"] = 0.0421
    assert "p=0.042" in right_label(row)


def test_nothing_to_draw_without_pairs():
    assert draw_forest(pd.DataFrame(), PLANNERS, 0.95) is None
