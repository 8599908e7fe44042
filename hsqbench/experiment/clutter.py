"""VGN/GIGA-comparable clutter metrics of packed and pile rounds, recomputed from the attempts.

VGN (Breyer et al. 2020) and GIGA (Jiang et al. 2021) end a clutter-removal round when the table
is clear, after two consecutive failed grasps, or at the first step where the planner finds no
grasp; that step is not a grasp attempt. They report GSR = successful grasps / grasps executed
and the declutter rate DR = successful grasps / objects presented (GIGA's
``clutter_removal.run``). VGN's own ``percent_cleared`` (its ``clutter_removal.Data``) is the
same ratio over the rounds with at least one grasp executed only (it joins the rounds to their
logged grasps, so a round that ends before its first grasp leaves its objects out).

Our rounds (:mod:`hsqbench.sim.stop_rule`) share the first two rules but count "no grasp found"
as a failed attempt and go on. Up to the first such attempt a round is the same under both rules
(the same attempts, the same scene), so their numbers follow from our rows: cut each round at its
first ``no_grasp_found`` attempt, and count successes and attempts before it. A run made with
``stop_on_no_grasp: true`` needs no cut. Our attempt cap and a simulation that became unstable
end a round in both counts.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.stats import Rate
from hsqbench.sim.stop_rule import NO_GRASP_FOUND

CLUTTER_CSV = "clutter_vgn.csv"
KINDS = ("packed", "pile")


def vgn_round(outcomes: list[str], successes: list[bool]) -> tuple[int, int, bool]:
    """(successful grasps, grasps executed, cut short) of one round's attempts in order, under
    VGN's rule: the round ends before its first attempt without a grasp."""
    cut = outcomes.index(NO_GRASP_FOUND) if NO_GRASP_FOUND in outcomes else len(outcomes)
    return int(sum(successes[:cut])), cut, cut < len(outcomes)


def clutter_table(data: RunData) -> pd.DataFrame:
    """One row per round kind and planner: VGN-rule GSR and declutter rate with Wilson
    intervals, beside our GSR and CR of the same rounds."""
    attempts, rounds = data.attempts, data.rounds
    rows: list[dict[str, Any]] = []
    if rounds.empty:
        return pd.DataFrame()
    ok = attempts[attempts["status"] == STATUS_OK]
    by_key = {k: g.sort_values("attempt_index") for k, g in ok.groupby("trial_key")}
    for kind in KINDS:
        done = rounds[
            rounds["trial_key"].str.startswith(f"{kind}/") & (rounds["status"] == STATUS_OK)
        ]
        for p in data.planners:
            mine = done[done["planner"] == p]
            if mine.empty:
                continue
            k = n = cut = cleared = presented = ours_k = ours_n = pc_n = 0
            for key, n_objects, n_cleared in zip(
                mine["trial_key"], mine["n_objects"], mine["n_cleared"], strict=True
            ):
                g = by_key.get(key)
                outcomes = [] if g is None else [str(o) for o in g["outcome"]]
                wins = [] if g is None else list(g["success"].to_numpy(dtype=float) > 0)
                rk, rn, rcut = vgn_round(outcomes, wins)
                k, n, cut = k + rk, n + rn, cut + rcut
                pc_n += int(n_objects) if rn else 0  # VGN's percent_cleared: rounds with a grasp
                ours_k, ours_n = ours_k + sum(wins), ours_n + len(wins)
                cleared, presented = cleared + int(n_cleared), presented + int(n_objects)
            gsr = Rate.of(k, n, data.confidence) if n else None
            dr = Rate.of(k, presented, data.confidence)
            rows.append(
                {
                    "experiment": kind,
                    "planner": p,
                    "rounds": len(mine),
                    "rounds_cut": cut,
                    "vgn_successes": k,
                    "vgn_attempts": n,
                    "vgn_gsr_percent": np.nan if gsr is None else 100 * gsr.value,
                    "vgn_gsr_low_percent": np.nan if gsr is None else 100 * gsr.low,
                    "vgn_gsr_high_percent": np.nan if gsr is None else 100 * gsr.high,
                    "declutter_percent": 100 * dr.value,
                    "declutter_low_percent": 100 * dr.low,
                    "declutter_high_percent": 100 * dr.high,
                    "objects_presented": presented,
                    "vgn_percent_cleared": 100 * k / pc_n if pc_n else np.nan,
                    "our_gsr_percent": 100 * ours_k / ours_n if ours_n else np.nan,
                    "our_cr_percent": 100 * cleared / presented,
                }
            )
    return pd.DataFrame(rows)


def render_clutter(data: RunData, table: pd.DataFrame) -> list[str]:
    """Markdown lines of the VGN/GIGA-comparable section (none without packed or pile rounds)."""
    if table.empty:
        return []
    conf = f"{100 * data.confidence:g} %"
    out = [
        "## Clutter metrics as VGN and GIGA count them",
        "",
        "The same rounds, counted as VGN and GIGA count theirs: a round also ends at the first "
        "attempt without a grasp, which is not an attempt; declutter rate = successful grasps / "
        "objects presented (GIGA); VGN's % cleared leaves out rounds without any grasp. Set these "
        "beside their papers' GSR and DR, not ours. Rounds cut: rounds that end earlier under "
        "their rule.",
        "",
    ]
    heads = ["experiment", "planner", "GSR (VGN rule)", f"{conf} CI", "k/n", "declutter rate",
             f"{conf} CI", "VGN % cleared", "our GSR", "our CR", "rounds cut"]  # fmt: skip
    out += ["| " + " | ".join(heads) + " |", "|" + "|".join(" --- " for _ in heads) + "|"]
    for _, r in table.iterrows():
        gsr_ok = np.isfinite(r["vgn_gsr_percent"])
        cells = [
            str(r["experiment"]),
            method_label(r["planner"]),
            f"{r['vgn_gsr_percent']:.1f}" if gsr_ok else "—",
            f"[{r['vgn_gsr_low_percent']:.1f}, {r['vgn_gsr_high_percent']:.1f}]" if gsr_ok else "—",
            f"{int(r['vgn_successes'])}/{int(r['vgn_attempts'])}",
            f"{r['declutter_percent']:.1f}",
            f"[{r['declutter_low_percent']:.1f}, {r['declutter_high_percent']:.1f}]",
            f"{r['vgn_percent_cleared']:.1f}" if np.isfinite(r["vgn_percent_cleared"]) else "—",
            f"{r['our_gsr_percent']:.1f}" if np.isfinite(r["our_gsr_percent"]) else "—",
            f"{r['our_cr_percent']:.1f}",
            f"{int(r['rounds_cut'])}/{int(r['rounds'])}",
        ]
        out.append("| " + " | ".join(cells) + " |")
    return [*out, ""]
