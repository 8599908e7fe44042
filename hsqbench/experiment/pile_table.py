"""Table IV: pile scenes (objects heaped and touching), GSR and CR per planner.

Measured rows come from the run's ``pile`` rounds, defined as Table II's: GSR = successful
attempts / attempts (no grasp found and the planner's own error count as failed attempts),
CR = objects removed / objects presented, intervals over rounds (cluster bootstrap). The
oracle's row (privileged: true meshes) is the hand's ceiling on the same piles. Beside them,
GIGA's reported simulated pile numbers, as context only: another harness (PyBullet, one noisy
depth view, its own objects, VGN's stop rule), not a like-for-like comparison.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.clutter import rates_over_rounds
from hsqbench.experiment.results import STATUS_ERROR, STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.stats import Rate
from hsqbench.sim.outcome import Outcome

TABLE4_CSV = "table4_pile.csv"
EXPERIMENT = "pile"
CONTEXT = "reported, simulation, other harness"
GIGA_PILE = {
    "method": "GIGA (pile)",
    "source": CONTEXT,
    "gsr_percent": 69.3,
    "cr_percent": 49.8,
    "reference": (
        "Jiang et al. 2021 (GIGA), simulated pile scenes, one noisy depth view: PyBullet, their "
        "objects and stop rule (a round also ends when no grasp is found); CR is their "
        "`declutter_rate`, successful grasps / objects of all rounds (the section on VGN and "
        "GIGA's counts gives ours)"
    ),
}


def _rate(k: int, n: int, confidence: float) -> dict[str, float]:
    if n == 0:
        return {"rate": np.nan, "low": np.nan, "high": np.nan}
    r = Rate.of(k, n, confidence)
    return {"rate": 100 * r.value, "low": 100 * r.low, "high": 100 * r.high}


def table4(data: RunData) -> pd.DataFrame:
    """One row per planner that ran pile rounds, then GIGA's reported row; empty without piles."""
    from hsqbench.experiment.graspable import method_label

    attempts, rounds = data.attempts, data.rounds
    if attempts.empty or not (attempts["experiment"] == EXPERIMENT).any():
        return pd.DataFrame()
    pile_rounds = rounds[rounds["trial_key"].str.startswith(f"{EXPERIMENT}/")]
    rows: list[dict[str, Any]] = []
    for p in data.planners:
        mine = attempts[(attempts["experiment"] == EXPERIMENT) & (attempts["planner"] == p)]
        if mine.empty:
            continue
        ok = mine[mine["status"] == STATUS_OK]
        done = pile_rounds[(pile_rounds["planner"] == p) & (pile_rounds["status"] == STATUS_OK)]
        successes, tried = int(ok["success"].sum()), len(ok)
        cleared, presented = int(done["n_cleared"].sum()), int(done["n_objects"].sum())
        gsr = _rate(successes, tried, data.confidence)
        cr = _rate(cleared, presented, data.confidence)
        # Intervals over rounds: the objects and grasps of a pile are not independent.
        over = rates_over_rounds(ok, done, data.confidence)
        gsr["low"], gsr["high"] = over["gsr_ci_low_percent"], over["gsr_ci_high_percent"]
        cr["low"], cr["high"] = over["cr_ci_low_percent"], over["cr_ci_high_percent"]
        rows.append(
            {
                "method": method_label(p),
                "source": data.source(p),
                "gsr_percent": gsr["rate"],
                "gsr_ci_low_percent": gsr["low"],
                "gsr_ci_high_percent": gsr["high"],
                "successes": successes,
                "attempts": tried,
                "cr_percent": cr["rate"],
                "cr_ci_low_percent": cr["low"],
                "cr_ci_high_percent": cr["high"],
                "objects_cleared": cleared,
                "objects_presented": presented,
                "rounds": len(done),
                "planner_errors": int((ok["outcome"] == str(Outcome.PLANNER_ERROR)).sum()),
                "errors": int((mine["status"] == STATUS_ERROR).sum()),
                "reference": "",
            }
        )
    rows.append(dict(GIGA_PILE))
    return pd.DataFrame(rows)


def _pct(v: Any) -> str:
    return "" if v is None or not np.isfinite(v) else f"{v:.1f}"


def _ci(row: pd.Series, prefix: str) -> str:
    low = row.get(f"{prefix}ci_low_percent", np.nan)
    if low is None or not np.isfinite(low):
        return "—"
    return f"[{low:.1f}, {row[f'{prefix}ci_high_percent']:.1f}]"


def render_table4(data: RunData, t4: pd.DataFrame) -> list[str]:
    """Markdown lines of Table IV (none when the run has no pile rounds)."""
    if t4.empty:
        return []
    conf = f"{100 * data.confidence:g} %"
    heads = ["method", "GSR", f"GSR {conf} CI", "k/n", "CR", f"CR {conf} CI", "cleared/presented"]
    heads += ["rounds", "planner errors", "infrastructure errors", "source"]
    measured = t4[t4["source"] != CONTEXT]
    context = t4[t4["source"] == CONTEXT]
    lines = ["## Table IV: pile scenes, GSR and CR (%)", ""]
    ceiling = measured["method"].str.endswith("(privileged)").any()
    lines += [
        "Objects dropped into a heap (touching, at random orientations), cleared with the packed "
        "rounds' stop rule."
        + (
            " The privileged oracle's row is the hand's ceiling on the same piles."
            if ceiling
            else ""
        ),
        "",
        "| " + " | ".join(heads) + " |",
        "|" + "|".join(" --- " for _ in heads) + "|",
    ]
    for _, r in measured.iterrows():
        cells = [
            str(r["method"]),
            _pct(r["gsr_percent"]),
            _ci(r, "gsr_"),
            f"{int(r['successes'])}/{int(r['attempts'])}",
            _pct(r["cr_percent"]),
            _ci(r, "cr_"),
            f"{int(r['objects_cleared'])}/{int(r['objects_presented'])}",
            str(int(r["rounds"])),
            str(int(r["planner_errors"])),
            str(int(r["errors"])),
            str(r["source"]),
        ]
        lines.append("| " + " | ".join(cells) + " |")
    # The context rows, set apart: other harness, other objects, other rule.
    lines.append(
        "| " + " | ".join(["*other harness, for context:*"] + [""] * (len(heads) - 1)) + " |"
    )
    for _, r in context.iterrows():
        cells = [str(r["method"]), _pct(r["gsr_percent"]), "—", "—", _pct(r["cr_percent"])]
        cells += ["—", "—", "—", "—", "—", str(r["source"])]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "GSR and CR intervals over rounds (cluster bootstrap): a pile's objects and "
              "grasps are not independent.", ""]  # fmt: skip
    lines += [*(f"- {r['method']}: {r['reference']}." for _, r in context.iterrows()), ""]
    return lines
