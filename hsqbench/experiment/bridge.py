"""The bridge from VGN/GIGA's clutter removal to the harness's protocol, one change at a time
(docs/clutter-removal.md): runs of the same rounds under successive protocols, each step's
declutter rate paired with the step before it, round by round.

The rounds of two steps pair up by draw (base seed and round index) when they present the same
objects (the clutter protocols generate the same scene for a draw whatever executes it). Per
planner and step: GSR and declutter rate counted as VGN and GIGA count them
(:mod:`hsqbench.experiment.clutter`), and the declutter rate minus the previous step's over the
paired rounds (:class:`~hsqbench.experiment.over_clusters.ClusterDifference`: rounds are the
units, the interval a cluster bootstrap, the p an exact swap test).

    python -m hsqbench.experiment.bridge RUN_0 RUN_1 [RUN_2 ...] [--kind packed]
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.clutter import round_counts
from hsqbench.experiment.markdown import p_text, signed_pp
from hsqbench.experiment.over_clusters import ClusterDifference


def bridge_table(
    steps: Sequence[tuple[str, Any]], kind: str = "packed", confidence: float = 0.95
) -> pd.DataFrame:
    """One row per planner and step (``steps``: (name, run data) in order): GSR and declutter
    rate of the step, and its declutter rate's paired difference to the step before."""
    rows: list[dict[str, Any]] = []
    planners = [p for p in steps[0][1].planners if all(p in d.planners for _, d in steps)]
    for p in planners:
        before: pd.DataFrame | None = None
        for name, data in steps:
            mine = round_counts(data, kind, p)
            k, n, presented = mine["vgn_k"].sum(), mine["vgn_n"].sum(), mine["presented"].sum()
            row: dict[str, Any] = {
                "planner": p,
                "step": name,
                "rounds": len(mine),
                "gsr_percent": 100 * k / n if n else np.nan,
                "gsr_k": int(k),
                "gsr_n": int(n),
                "declutter_percent": 100 * k / presented if presented else np.nan,
                "objects_presented": int(presented),
            }
            if before is not None:
                row |= _paired(mine, before, confidence)
            rows.append(row)
            before = mine
    return pd.DataFrame(rows)


def _paired(mine: pd.DataFrame, before: pd.DataFrame, confidence: float) -> dict[str, Any]:
    """Declutter rate of ``mine`` minus ``before`` over the draws both ran with the same
    objects presented."""
    common = [
        i
        for i in mine.index.intersection(before.index)
        if mine.at[i, "objects"] == before.at[i, "objects"]
        and mine.at[i, "presented"] == before.at[i, "presented"]
    ]
    if not common:
        return {"paired_rounds": 0}
    a, b = mine.loc[common], before.loc[common]
    c = ClusterDifference.of(a["vgn_k"], a["presented"], b["vgn_k"], b["presented"], confidence)
    return {
        "paired_rounds": c.clusters,
        "dr_vs_before_pp": 100 * c.difference,
        "dr_vs_before_low_pp": 100 * c.low,
        "dr_vs_before_high_pp": 100 * c.high,
        "dr_vs_before_p": c.p_value,
    }


def render_bridge(table: pd.DataFrame, confidence: float = 0.95) -> list[str]:
    """Markdown lines of the bridge table."""
    conf = f"{100 * confidence:g} %"
    heads = ["planner", "step", "rounds", "GSR (their rule)", "k/n", "declutter rate",
             f"vs the step before (pp) [{conf} CI], p", "paired rounds"]  # fmt: skip
    out = ["| " + " | ".join(heads) + " |", "|" + "|".join(" --- " for _ in heads) + "|"]
    for _, r in table.iterrows():
        vs, paired = "—", "—"
        if np.isfinite(r.get("dr_vs_before_pp", np.nan)):
            low, high = r["dr_vs_before_low_pp"], r["dr_vs_before_high_pp"]
            ci = f" [{signed_pp(low)}, {signed_pp(high)}]" if np.isfinite(low) else ""
            vs = f"{signed_pp(r['dr_vs_before_pp'])}{ci}, p {p_text(r['dr_vs_before_p'])}"
            paired = str(int(r["paired_rounds"]))
        cells = [
            str(r["planner"]),
            str(r["step"]),
            str(int(r["rounds"])),
            f"{r['gsr_percent']:.1f}",
            f"{int(r['gsr_k'])}/{int(r['gsr_n'])}",
            f"{r['declutter_percent']:.1f}",
            vs,
            paired,
        ]
        out.append("| " + " | ".join(cells) + " |")
    return out


def main(argv: Sequence[str] | None = None) -> None:
    from hsqbench.experiment.run_data import load_run

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="run folders, the bridge's steps in order")
    parser.add_argument("--kind", choices=("packed", "pile"), default="packed")
    args = parser.parse_args(argv)
    if len(args.runs) < 2:
        parser.error("name at least two runs: the steps of the bridge")
    steps = [(Path(r).name, load_run(r)) for r in args.runs]
    confidence = steps[0][1].confidence
    print("\n".join(render_bridge(bridge_table(steps, args.kind, confidence), confidence)))


if __name__ == "__main__":
    main()
