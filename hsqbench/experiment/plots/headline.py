"""The headline figure of a run: GSR and CR per planner with Wilson intervals, over all
presentations and over the graspable ones, a panel per protocol and rate (isolated GSR; packed
GSR and CR; pile GSR and CR), the papers' reported rows beside them as hollow markers."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.graspable import cr_graspable, gsr_graspable, method_label
from hsqbench.experiment.paired_table import finished_rounds
from hsqbench.experiment.pile_table import GIGA_PILE
from hsqbench.experiment.plots.canvas import figure, n_text, row_order, span
from hsqbench.experiment.plots.palette import REPORTED, planner_colours
from hsqbench.experiment.reported import reported_rows
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.stats import Rate
from hsqbench.planner.registry import PRIVILEGED

#: (experiment, rate, panel title) in panel order; a panel is drawn when the run has its rows.
PANELS = (
    ("isolated", "gsr", "isolated GSR"),
    ("packed", "gsr", "packed GSR"),
    ("packed", "cr", "packed CR"),
    ("pile", "gsr", "pile GSR"),
    ("pile", "cr", "pile CR"),
)
_OFFSET = 0.17  # rows: "all" above the planner's line, "graspable" below it


def _cells(exp: str, rate: str, planner: str, scope: str, r: Rate | None) -> list[dict]:
    if r is None:
        return []
    return [{"experiment": exp, "rate": rate, "planner": planner, "scope": scope, "n": r.trials,
             "percent": 100 * r.value, "low": 100 * r.low, "high": 100 * r.high}]  # fmt: skip


def measured_rates(data: RunData) -> pd.DataFrame:
    """One row per experiment, rate (gsr, cr), planner and scope (all, graspable): the rate in
    percent with its Wilson interval and its count ``n`` (attempts, or objects for CR)."""
    rows: list[dict[str, Any]] = []
    df, conf = data.attempts, data.confidence
    for exp in dict.fromkeys(e for e, _, _ in PANELS):
        ok = df[(df["experiment"] == exp) & (df["status"] == STATUS_OK)] if len(df) else df
        done = finished_rounds(data.rounds, exp)
        for p in data.planners:
            mine = ok[ok["planner"] == p] if len(ok) else ok
            if len(mine):
                rows += _cells(
                    exp, "gsr", p, "all", Rate.of(int(mine["success"].sum()), len(mine), conf)
                )
                if exp == "isolated":  # packed GSR is not conditioned (graspable.py)
                    rows += _cells(exp, "gsr", p, "graspable", gsr_graspable(mine, conf))
            rounds = done[done["planner"] == p] if exp != "isolated" and len(done) else done[:0]
            if int(rounds["n_objects"].sum() if len(rounds) else 0):
                cleared, shown = int(rounds["n_cleared"].sum()), int(rounds["n_objects"].sum())
                rows += _cells(exp, "cr", p, "all", Rate.of(cleared, shown, conf))
                rows += _cells(exp, "cr", p, "graspable", cr_graspable(rounds, conf))
    cols = ["experiment", "rate", "planner", "scope", "n", "percent", "low", "high"]
    return pd.DataFrame(rows, columns=cols)


def reported_points(meta: dict) -> pd.DataFrame:
    """The papers' reported rates (no intervals) that describe the run of ``meta``: label,
    experiment, rate, percent."""
    rows = []
    for exp in ("isolated", "packed"):
        for r in reported_rows(exp, meta):
            rows.append(
                {"label": r.method, "experiment": exp, "rate": "gsr", "percent": r.gsr_percent}
            )
            if r.cr_percent is not None:
                rows.append(
                    {"label": r.method, "experiment": exp, "rate": "cr", "percent": r.cr_percent}
                )
    for rate in ("gsr", "cr"):
        rows.append({"label": GIGA_PILE["method"], "experiment": "pile", "rate": rate,
                     "percent": GIGA_PILE[f"{rate}_percent"]})  # fmt: skip
    return pd.DataFrame(rows)


def _row_labels(planners: list[str], reported: list[str]) -> list[str]:
    return [method_label(p) for p in planners] + [f"{r}, reported" for r in reported]


def draw_headline(data: RunData, with_reported: bool = True) -> Any:
    """The headline figure (a matplotlib Figure; None when the run has no measured rows)."""
    rates = measured_rates(data)
    if rates.empty:
        return None
    panels = [(e, r, t) for e, r, t in PANELS
              if ((rates["experiment"] == e) & (rates["rate"] == r)).any()]  # fmt: skip
    planners = row_order(data.planners, rates["planner"])
    shown = {(e, r) for e, r, _ in panels}
    rep = reported_points(data.meta)
    keep = [(e, r) in shown for e, r in zip(rep["experiment"], rep["rate"], strict=True)]
    rep = rep[[with_reported and k for k in keep]]
    reported = list(dict.fromkeys(rep["label"]))
    labels = _row_labels(planners, reported)
    ncols = min(3, len(panels))
    nrows = int(np.ceil(len(panels) / ncols))
    fig = figure(3.0 * ncols + 1.9, nrows * (0.3 * len(labels) + 1.0) + 0.8)
    axes = fig.subplots(nrows, ncols, sharey=True, squeeze=False).ravel()
    colours = planner_colours(data.planners)
    for ax, (exp, rate, title) in zip(axes[: len(panels)], panels, strict=True):
        mine = rates[(rates["experiment"] == exp) & (rates["rate"] == rate)]
        _draw_measured(ax, mine, planners, colours)
        theirs = rep[(rep["experiment"] == exp) & (rep["rate"] == rate)]
        y = [len(planners) + reported.index(label) for label in theirs["label"]]
        ax.plot(theirs["percent"], y, "o", mfc="none", mec=REPORTED, ms=6, ls="none",
                label="reported")  # fmt: skip
        _style(ax, mine, title, rate, labels, len(planners))
        n_methods = sum(p not in PRIVILEGED for p in planners)
        if n_methods < len(planners):  # the oracle's rows: set apart as a ceiling
            ax.axhline(n_methods - 0.5, color="0.6", lw=0.8, ls=":")
    for ax in axes[len(panels) :]:
        ax.set_visible(False)
    _legend(fig, rates, bool(reported), any(p in PRIVILEGED for p in planners))
    level = f"{100 * data.confidence:g} %"
    fig.suptitle(f"{data.meta.get('run', 'run')}: success per planner ({level} Wilson intervals)",
                 fontsize=10)  # fmt: skip
    return fig


def _draw_measured(ax: Any, mine: pd.DataFrame, planners: list[str], colours: dict) -> None:
    for y, p in enumerate(planners):
        for scope, marker, dy in (("all", "o", -_OFFSET), ("graspable", "D", _OFFSET)):
            cell = mine[(mine["planner"] == p) & (mine["scope"] == scope)]
            if cell.empty:
                continue
            c = cell.iloc[0]
            err = [[c["percent"] - c["low"]], [c["high"] - c["percent"]]]
            ax.errorbar([c["percent"]], [y + dy], xerr=err, fmt=marker, color=colours[p],
                        ms=5 if marker == "o" else 4, capsize=2, lw=1.2,
                        label=f"{p} ({scope})")  # fmt: skip


def _style(ax: Any, mine: pd.DataFrame, title: str, rate: str, labels: list[str],
           n_measured: int) -> None:  # fmt: skip
    counts = mine.loc[mine["scope"] == "all", "n"].astype(int).tolist()
    graspable = mine.loc[mine["scope"] == "graspable", "n"].astype(int).tolist()
    n = n_text(counts, "attempts" if rate == "gsr" else "objects")
    if graspable:
        n += f", {span(graspable)} graspable"
    ax.set_title(f"{title}\n{n}", fontsize=9)
    ax.set_xlim(-3, 103)
    ax.set_xticks([0, 20, 40, 60, 80, 100])
    ax.set_xlabel("%", fontsize=8)
    ax.tick_params(labelsize=8)
    ax.grid(axis="x", alpha=0.3)
    ax.set_yticks(np.arange(len(labels)), labels)
    ax.set_ylim(len(labels) - 0.5, -0.5)  # first planner on top
    if n_measured < len(labels):
        ax.axhline(n_measured - 0.5, color="0.6", lw=0.8)
    for tick in ax.get_yticklabels()[n_measured:]:
        tick.set_color("0.35")
        tick.set_fontstyle("italic")


def _legend(fig: Any, rates: pd.DataFrame, reported: bool, oracle: bool) -> None:
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], marker="o", color="0.3", ls="-", label="all presentations")]
    if (rates["scope"] == "graspable").any():
        handles.append(Line2D([], [], marker="D", color="0.3", ms=4, ls="-",
                              label="graspable presentations (oracle found a grasp)"))  # fmt: skip
    if reported:
        handles.append(Line2D([], [], marker="o", mfc="none", mec=REPORTED, ls="none",
                              label="reported by the papers (no interval)"))  # fmt: skip
    if oracle:
        handles.append(Line2D([], [], marker="o", color=planner_colours(["oracle"])["oracle"],
                              ls="-", label="oracle: privileged (true meshes), a ceiling"))  # fmt: skip
    ncols = 2 if fig.get_size_inches()[0] >= 7 else 1  # two long entries side by side need 7 in
    fig.legend(handles=handles, loc="outside lower center", ncols=ncols, fontsize=8, frameon=False)
