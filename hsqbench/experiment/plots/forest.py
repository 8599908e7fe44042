"""The paired comparison as a forest plot: each planner's difference to the reference planner
on the same presentations (``paired.csv``, :mod:`hsqbench.experiment.paired_table`), a panel
per comparison (isolated GSR, packed and pile CR and GSR). The thick bar is the interval over
objects or rounds (cluster bootstrap); the thin one below it, for isolated GSR, Newcombe's
interval over the presentations; a column beside each panel gives the numbers and the verdict
(from the Holm-adjusted p) in words."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.plots.canvas import figure, row_order, span
from hsqbench.experiment.plots.palette import planner_colours

_CLUSTER_DY = 0.28  # the presentations' interval sits this far below the clusters' one


def _pp(v: float) -> str:
    return f"{v:+.1f}" if np.isfinite(v) else "—"


def _p(p: float) -> str:
    return "p<0.001" if p < 0.001 else f"p={p:.2g}"


def right_label(r: pd.Series) -> str:
    """``"-6.7 [-11.8, -1.9]  12:30  p=0.003  worse"``: difference, interval over clusters,
    won:lost (pairs; rounds of GSR have none), Holm-adjusted p, verdict."""
    won_lost = (
        f"{int(r['only_planner'])}:{int(r['only_reference'])}  "
        if np.isfinite(r.get("only_planner", np.nan))
        else ""
    )
    return (
        f"{_pp(r['difference_pp'])} [{_pp(r['ci_low_pp'])}, {_pp(r['ci_high_pp'])}]  "
        f"{won_lost}{_p(r['p_holm'])}  {r['verdict']}"
    )


def draw_forest(paired: pd.DataFrame, planners: list[str], confidence: float) -> Any:
    """The figure (None when nothing was paired); ``planners`` sets the colours and row order."""
    if paired.empty:
        return None
    reference = str(paired["reference"].iloc[0])
    comparisons = list(dict.fromkeys(paired["comparison"]))
    order = {p: i for i, p in enumerate(row_order(planners, paired["planner"]))}
    sizes = [int((paired["comparison"] == c).sum()) for c in comparisons]
    fig = figure(9.0, sum(0.34 * n + 1.05 for n in sizes) + 0.6)
    # A column of plots and one of numbers beside them: the plots line up whatever the text.
    grid = fig.subplots(len(comparisons), 2, squeeze=False, sharey="row",
                        height_ratios=[n + 2 for n in sizes], width_ratios=[3.0, 1.75])  # fmt: skip
    colours = planner_colours(planners)
    for (ax, text), comparison in zip(grid, comparisons, strict=True):
        rows = paired[paired["comparison"] == comparison]
        rows = rows.sort_values("planner", key=lambda s: s.map(order), kind="stable")
        rows = rows.reset_index(drop=True)
        _panel(ax, rows, colours, comparison, reference)
        _numbers(text, rows)
    _legend(fig)
    level = f"{100 * confidence:g} %"
    fig.suptitle(f"Paired difference to {reference} on the same presentations ({level} "
                 "intervals; p: sign-flip over clusters, Holm-adjusted)", fontsize=10)  # fmt: skip
    return fig


def _panel(ax: Any, rows: pd.DataFrame, colours: dict, comparison: str, reference: str) -> None:
    y = np.arange(len(rows))
    for i, r in rows.iterrows():
        c = colours.get(str(r["planner"]), "0.3")
        d = r["difference_pp"]
        # Too few clusters for a bootstrap: the point alone.
        err = [[d - r["ci_low_pp"]], [r["ci_high_pp"] - d]] if np.isfinite(r["ci_low_pp"]) else None
        ax.errorbar([d], [i], xerr=err, fmt="o", color=c, ms=6, lw=2.2, capsize=3,
                    label=f"{r['planner']} (clusters)")  # fmt: skip
        lo, hi = r["presentations_ci_low_pp"], r["presentations_ci_high_pp"]
        if np.isfinite(lo) and np.isfinite(hi):
            ax.errorbar([d], [i + _CLUSTER_DY], xerr=[[d - lo], [hi - d]], fmt="none",
                        ecolor=c, lw=0.9, capsize=2, alpha=0.8,
                        label=f"{r['planner']} (presentations)")  # fmt: skip
    ax.axvline(0, color="black", lw=0.8)
    bounds = rows[["difference_pp", "ci_low_pp", "ci_high_pp", "presentations_ci_low_pp",
                   "presentations_ci_high_pp"]]  # fmt: skip
    ax.set_xlim(*_limits(bounds.to_numpy(dtype=float)))
    ax.set_ylim(len(rows) - 0.4, -0.6)
    ax.set_yticks(y, [method_label(str(p)) for p in rows["planner"]])
    ax.tick_params(labelsize=8)
    ax.grid(axis="x", alpha=0.3)
    clusters = rows["clusters"].astype(int).tolist()
    what = str(rows["unit"].iloc[0])
    ax.set_title(f"{comparison}: planner − {reference}, over {span(clusters)} {what}", fontsize=9)
    ax.set_xlabel("difference (percentage points)", fontsize=8)


def _numbers(ax: Any, rows: pd.DataFrame) -> None:
    """The right column: each row's numbers and verdict, level with its interval."""
    ax.axis("off")
    ax.set_xlim(0, 1)
    for i, r in rows.iterrows():
        ax.text(0.0, i, right_label(r), va="center", ha="left", fontsize=7.5)
    ax.set_title("difference [interval]  won:lost  p Holm  verdict", fontsize=8, loc="left")


def _limits(bounds: np.ndarray) -> tuple[float, float]:
    """From the lowest to the highest bound, zero always inside, with a margin."""
    finite = bounds[np.isfinite(bounds)]
    lo, hi = min(0.0, *finite), max(0.0, *finite)
    pad = max(2.0, 0.06 * (hi - lo))
    return lo - pad, hi + pad


def _legend(fig: Any) -> None:
    from matplotlib.lines import Line2D

    handles = [
        Line2D(
            [],
            [],
            marker="o",
            color="0.3",
            lw=2.2,
            label="over objects or rounds (cluster bootstrap)",
        ),
        Line2D([], [], color="0.3", lw=0.9, label="over presentations (Newcombe)"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=8, frameon=False)
