"""Isolated GSR per object (a heat map, objects by planners) and planning time per planner."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from matplotlib.ticker import FuncFormatter

from hsqbench.experiment.plots.canvas import figure, n_text, row_order
from hsqbench.experiment.plots.palette import planner_colours
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData


def draw_gsr_per_object(data: RunData, t1o: pd.DataFrame) -> Any:
    """A heat map of isolated GSR, an object a row and a planner a column, the rate written in
    each cell (readable for 15 objects or 40); None without a per-object table."""
    if t1o.empty:
        return None
    planners = row_order(data.planners, t1o["planner"])
    objects = [o for o in data.objects if o in set(t1o["object"])]
    grid = t1o.pivot_table(index="object", columns="planner", values="gsr_percent")
    grid = grid.reindex(index=objects, columns=planners).to_numpy(dtype=float)
    fig = figure(2.4 + 0.85 * len(planners), 1.3 + 0.22 * len(objects))
    ax = fig.add_subplot()
    image = ax.imshow(grid, cmap="cividis", vmin=0, vmax=100, aspect="auto")
    for (i, j), v in np.ndenumerate(grid):
        if np.isfinite(v):
            ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=7,
                    color="white" if v < 55 else "black")  # fmt: skip
    ax.set_yticks(np.arange(len(objects)), objects, fontsize=7)
    ax.set_xticks(np.arange(len(planners)), planners, rotation=30, ha="left", fontsize=8)
    ax.xaxis.tick_top()
    colours = planner_colours(data.planners)
    for tick, p in zip(ax.get_xticklabels(), planners, strict=True):
        tick.set_color(colours[p])
    ax.tick_params(length=0)
    counts = t1o["attempts"].astype(int).tolist()
    ax.set_title(f"Isolated GSR per object (%), {n_text(counts, 'attempts')} per cell",
                 fontsize=9)  # fmt: skip
    fig.colorbar(image, ax=ax, shrink=0.5, label="GSR (%)")
    return fig


def draw_planning_time(data: RunData) -> Any:
    """Box plots of planning seconds per attempt, a box per planner; None without times."""
    ok = data.attempts[data.attempts["status"] == STATUS_OK] if len(data.attempts) else None
    planners, series = [], []
    for p in row_order(data.planners, data.planners) if ok is not None else []:
        t = ok.loc[ok["planner"] == p, "planning_s"].to_numpy(dtype=float)
        t = t[np.isfinite(t)]
        if t.size:
            planners.append(p)
            series.append(t)
    if not planners:
        return None
    colours = planner_colours(data.planners)
    fig = figure(max(5.0, 0.9 * len(planners) + 2), 4.0)
    ax = fig.add_subplot()
    boxes = ax.boxplot(series, showfliers=True, patch_artist=True, flierprops={"ms": 2},
                       medianprops={"color": "black"})  # fmt: skip
    for box, p in zip(boxes["boxes"], planners, strict=True):
        box.set_facecolor(colours[p])
        box.set_alpha(0.6)
    ax.set_xticks(np.arange(1, len(planners) + 1), planners, rotation=20, ha="right", fontsize=8)
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))  # 0.1, 1, 10 (not 10^k)
    ax.set_ylabel("planning time per attempt (s)")
    ax.grid(axis="y", alpha=0.3)
    ax.set_title("Planning time (all experiments, log scale)", fontsize=10)
    return fig
