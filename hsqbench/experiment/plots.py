"""The plots of a run's report (PNG, matplotlib's Agg canvas, no pyplot global state)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData


def _figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure  # Agg canvas, no pyplot global state

    return Figure(figsize=(width, height), dpi=110, layout="constrained")


def plot_gsr_per_object(data: RunData, t1o: pd.DataFrame, path: Path) -> None:
    fig = _figure(max(6.0, 0.7 * len(data.objects) + 2), 4.2)
    ax = fig.add_subplot()
    planners = [p for p in data.planners if p in set(t1o["planner"])]
    width = 0.8 / max(1, len(planners))
    x = np.arange(len(data.objects))
    for i, p in enumerate(planners):
        sub = t1o[t1o["planner"] == p].set_index("object").reindex(data.objects)
        y = sub["gsr_percent"].to_numpy(dtype=float)
        err = np.vstack(
            [
                y - sub["ci_low_percent"].to_numpy(dtype=float),
                sub["ci_high_percent"].to_numpy(dtype=float) - y,
            ]
        )
        ax.bar(x + (i - (len(planners) - 1) / 2) * width, y, width, yerr=err, capsize=2, label=p)
    ax.set_xticks(x, data.objects, rotation=45, ha="right")
    ax.set_ylabel("GSR (%)")
    ax.set_ylim(0, 118)  # headroom for the legend above the 100 % bars
    ax.set_title(f"Isolated GSR per object ({100 * data.confidence:g} % Wilson intervals)")
    ax.legend(fontsize="small", ncols=max(1, len(planners)), loc="upper left")
    fig.savefig(path)


def plot_outcomes(outcomes: pd.DataFrame, path: Path) -> None:
    fig = _figure(max(5.0, 1.0 * len(outcomes) + 3), 4.2)
    ax = fig.add_subplot()
    labels = [f"{r['planner']}\n{r['experiment']}" for _, r in outcomes.iterrows()]
    bottom = np.zeros(len(outcomes))
    for col in [c for c in outcomes.columns if c not in ("experiment", "planner", "attempts")]:
        values = outcomes[col].to_numpy(dtype=float)
        if values.sum() == 0:
            continue
        ax.bar(labels, values, bottom=bottom, label=col)
        bottom += values
    ax.set_ylabel("attempts (error: trials)")
    ax.set_title("Outcome breakdown")
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.savefig(path)


def plot_planning_time(data: RunData, path: Path) -> None:
    ok = data.attempts[data.attempts["status"] == STATUS_OK]
    planners, series = [], []
    for p in data.planners:
        t = ok.loc[ok["planner"] == p, "planning_s"].to_numpy(dtype=float)
        t = t[np.isfinite(t)]
        if t.size:
            planners.append(p)
            series.append(t)
    fig = _figure(max(4.0, 1.2 * len(planners) + 2), 4.0)
    ax = fig.add_subplot()
    ax.boxplot(series, showfliers=True)
    ax.set_xticks(np.arange(1, len(planners) + 1), planners)
    ax.set_ylabel("planning time per attempt (s)")
    ax.set_title("Planning time (both experiments)")
    fig.savefig(path)
