"""How attempts end, per planner: a horizontal bar of outcome fractions (summing to 1 over the
planner's attempts), a panel per experiment. A planner's own error (``planner_error``) is one
of its attempts, a bar segment like any failure; trials that failed with an infrastructure
error are not attempts: they are counted in the panel's title, not in the bars."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.plots.canvas import figure, n_text, row_order
from hsqbench.experiment.plots.palette import OUTCOME_COLOURS
from hsqbench.sim.outcome import Outcome

OUTCOMES = tuple(str(o) for o in Outcome)
_LABEL_MIN = 0.08  # segments narrower than this carry no percentage (it would not fit)


def outcome_fractions(outcomes: pd.DataFrame) -> pd.DataFrame:
    """``outcomes.csv``'s counts as fractions of each row's attempts (rows without attempts
    dropped): columns experiment, planner, attempts, errors and one per outcome."""
    rows = outcomes[outcomes["attempts"] > 0]
    counts = rows[list(OUTCOMES)].to_numpy(dtype=float)
    fractions = counts / counts.sum(axis=1, keepdims=True)
    out = rows[["experiment", "planner", "attempts"]].reset_index(drop=True)
    out["errors"] = rows["error"].to_numpy(dtype=int) if "error" in rows else 0
    return pd.concat([out, pd.DataFrame(fractions, columns=list(OUTCOMES))], axis=1)


def draw_failures(outcomes: pd.DataFrame, planners: list[str]) -> Any:
    """The figure (None without attempts); ``planners`` sets the row order."""
    frac = outcome_fractions(outcomes)
    if frac.empty:
        return None
    experiments = list(dict.fromkeys(frac["experiment"]))
    rows = row_order(planners, frac["planner"])
    used = [o for o in OUTCOMES if frac[o].sum() > 0]
    width_in = 2.9 * len(experiments) + 1.9
    fig = figure(width_in, 0.32 * len(rows) + 1.9)
    axes = fig.subplots(1, len(experiments), sharey=True, squeeze=False).ravel()
    for ax, exp in zip(axes, experiments, strict=True):
        mine = frac[frac["experiment"] == exp].set_index("planner").reindex(rows)
        left = np.zeros(len(rows))
        for o in used:
            width = mine[o].fillna(0.0).to_numpy(dtype=float)
            ax.barh(np.arange(len(rows)), width, left=left, color=OUTCOME_COLOURS[o], label=o,
                    height=0.7, edgecolor="white", linewidth=0.5)  # fmt: skip
            for y in np.flatnonzero(width >= _LABEL_MIN):
                ax.text(left[y] + width[y] / 2, y, f"{100 * width[y]:.0f}", ha="center",
                        va="center", fontsize=7, color=_ink(OUTCOME_COLOURS[o]))  # fmt: skip
            left += width
        _style(ax, mine, exp, rows)
    handles, names = axes[0].get_legend_handles_labels()
    fig.legend(handles, [n.replace("_", " ") for n in names], loc="outside lower center",
               ncols=min(4, len(used), int(width_in / 1.7)), fontsize=8, frameon=False)  # fmt: skip
    fig.suptitle("How attempts end (% of each planner's attempts)", fontsize=10)
    return fig


def _style(ax: Any, mine: pd.DataFrame, exp: str, rows: list[str]) -> None:
    counts = mine["attempts"].dropna().astype(int).tolist()
    errors = int(mine["errors"].fillna(0).sum())
    extra = f"; {errors} error trial(s) left out" if errors else ""
    ax.set_title(f"{exp}\n{n_text(counts, 'attempts')} per planner{extra}", fontsize=9)
    ax.set_yticks(np.arange(len(rows)), [method_label(p) for p in rows])
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlim(0, 1)
    ax.set_xticks([0, 0.25, 0.5, 0.75, 1.0], ["0", "25", "50", "75", "100 %"])
    ax.tick_params(labelsize=8)


def _ink(colour: str) -> str:
    """Black or white text, whichever reads on ``colour`` (by its luminance)."""
    r, g, b = (int(colour[i : i + 2], 16) / 255 for i in (1, 3, 5))
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.55 else "white"
