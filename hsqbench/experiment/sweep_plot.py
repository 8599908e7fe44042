"""A sweep parameter's plot: the rate against the point, a line per planner with its Wilson
band; one panel per protocol and rate (isolated GSR; packed and pile GSR and CR)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.plots.palette import planner_colours


def _figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure  # Agg canvas, no pyplot global state

    return Figure(figsize=(width, height), dpi=110, layout="constrained")


#: (experiment, column prefix, title) of each rate a panel can show, in panel order.
RATES = (
    ("isolated", "gsr", "isolated GSR"),
    ("packed", "gsr", "packed GSR"),
    ("packed", "cr", "packed CR"),
    ("pile", "gsr", "pile GSR"),
    ("pile", "cr", "pile CR"),
)


def _n_text(rows: pd.DataFrame, prefix: str) -> str:
    counts = rows["n"] if prefix == "gsr" else rows["objects_presented"]
    lo, hi = int(counts.min()), int(counts.max())
    what = "attempts" if prefix == "gsr" else "objects"
    return f"n = {lo} {what}" if lo == hi else f"n = {lo}-{hi} {what}"


def plot_parameter(rows: pd.DataFrame, param: dict[str, Any], path: Path) -> None:
    """Write the plot of one parameter's rows of ``sweep.csv`` to ``path``."""
    draw_parameter(rows, param).savefig(path)


def draw_parameter(rows: pd.DataFrame, param: dict[str, Any]) -> Any:
    """The figure of one parameter's rows: a panel per protocol and rate, a planner keeping its
    colour in every panel (protocols may have run different planners)."""
    labels = [p["label"] for p in param["points"]]
    xs = (
        np.arange(len(labels), dtype=float)
        if param["categorical"]
        else np.array([p["x"] for p in param["points"]], dtype=float)
    )
    panels = [
        (proto, exp, prefix, title)
        for proto in dict.fromkeys(rows["protocol"])
        for exp, prefix, title in RATES
        if len(rows[(rows["protocol"] == proto) & (rows["experiment"] == exp)])
    ]
    fig = _figure(4.6 * min(3, len(panels)), 3.6 * int(np.ceil(len(panels) / 3)))
    level = round(100 * float(rows["confidence"].iloc[0]))
    colours = planner_colours(list(dict.fromkeys(rows["planner"])))
    for k, (proto, exp, prefix, title) in enumerate(panels):
        ax = fig.add_subplot(int(np.ceil(len(panels) / 3)), min(3, len(panels)), k + 1)
        mine = rows[(rows["protocol"] == proto) & (rows["experiment"] == exp)]
        for planner in dict.fromkeys(mine["planner"]):
            line = mine[mine["planner"] == planner].sort_values("point")
            x = xs[line["point"].to_numpy(dtype=int)]
            ax.plot(x, line[f"{prefix}_percent"], marker="o", label=planner, color=colours[planner])
            ax.fill_between(
                x,
                line[f"{prefix}_ci_low_percent"].to_numpy(dtype=float),
                line[f"{prefix}_ci_high_percent"].to_numpy(dtype=float),
                alpha=0.18,
                color=colours[planner],
            )
        ax.set_xticks(xs, labels, rotation=20 if max(map(len, labels)) > 6 else 0)
        ax.set_ylim(0, 100)
        ax.set_xlabel(param["axis"])
        ax.set_ylabel(f"{title} (%)")
        ax.set_title(
            f"{proto}: {title}\n{_n_text(mine, prefix)} per planner and point, "
            f"{level} % Wilson bands",
            fontsize=9,
        )
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return fig
