"""The report figures' shared canvas helpers (hsqbench.experiment.plots.canvas)."""

from __future__ import annotations

from hsqbench.experiment.plots.canvas import DPI, figure, n_text, row_order, span


def test_the_oracle_comes_last_and_absent_planners_are_left_out():
    order = row_order(["oracle", "hsq", "antipodal", "single-sq"], {"antipodal", "oracle", "hsq"})
    assert order == ["hsq", "antipodal", "oracle"]


def test_counts_read_as_one_number_or_a_range():
    assert span([450, 450]) == "450"
    assert n_text([251, 198, 236], "attempts") == "n = 198-251 attempts"


def test_figures_are_drawn_at_readme_resolution():
    fig = figure(8, 4)
    assert fig.get_dpi() == DPI == 150
    assert tuple(fig.get_size_inches()) == (8, 4)
