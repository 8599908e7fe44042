"""VGN/GIGA-comparable clutter metrics of packed and pile rounds, recomputed from the attempts.

VGN (Breyer et al. 2020) and GIGA (Jiang et al. 2021) end a clutter-removal round when the table
is clear, after two consecutive failed grasps, or at the first step where the planner finds no
grasp; that step is not a grasp attempt. They report GSR = successful grasps / grasps executed
and a declutter rate, which the two codes count differently when a round logs no grasp:

- GIGA's ``declutter_rate`` = successful grasps / objects of all rounds (UT-Austin-RPL/GIGA,
  src/vgn/experiments/clutter_removal.py: ``total_objs += sim.num_objects`` for every round,
  ``declutter_rate = 100.0 * success / total_objs``). This is the one reported here.
- VGN's ``percent_cleared`` (ethz-asl/vgn, src/vgn/experiments/clutter_removal.py,
  ``Data.percent_cleared``) sums the successes per round of the logged grasps and *inner*-merges
  them with the rounds, so a round that ended before its first grasp drops out of the
  denominator; it is shown beside GIGA's.

Our rounds (:mod:`hsqbench.sim.stop_rule`) share the first two rules but count "no grasp found"
as a failed attempt and go on. Up to the first such attempt a round is the same under both rules
(the same attempts, the same scene), so their numbers follow from our rows: cut each round at its
first attempt without a grasp (``no_grasp_found``, or the planner's own error,
``planner_error``), and count successes and attempts before it. A run made with
``stop_on_no_grasp: true`` needs no cut. Our attempt cap and a simulation that became unstable
end a round in both counts.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.cluster import N_RESAMPLES, rate_over_clusters
from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.holm import holm_verdicts
from hsqbench.experiment.markdown import p_text, signed_pp
from hsqbench.experiment.over_clusters import ClusterDifference
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.sim.stop_rule import NO_GRASP

CLUTTER_CSV = "clutter_vgn.csv"
KINDS = ("packed", "pile")


def vgn_round(outcomes: list[str], successes: list[bool]) -> tuple[int, int, bool]:
    """(successful grasps, grasps executed, cut short) of one round's attempts in order, under
    VGN's rule: the round ends before its first attempt without a grasp."""
    cut = next((i for i, o in enumerate(outcomes) if o in NO_GRASP), len(outcomes))
    return int(sum(successes[:cut])), cut, cut < len(outcomes)


def round_counts(data: RunData, kind: str, planner: str) -> pd.DataFrame:
    """:func:`_rounds` of one planner, from the run's finished attempts (for other modules:
    :mod:`hsqbench.experiment.bridge`)."""
    ok = data.attempts[data.attempts["status"] == STATUS_OK]
    by_key = {k: g.sort_values("attempt_index") for k, g in ok.groupby("trial_key")}
    return _rounds(data, kind, planner, by_key)


def _rounds(data: RunData, kind: str, planner: str, by_key: dict) -> pd.DataFrame:
    """Per finished ``kind`` round of ``planner``: VGN-rule successes and attempts, whether it
    was cut, our successes and attempts, objects presented and removed (indexed by draw)."""
    rounds = data.rounds
    done = rounds[
        rounds["trial_key"].str.startswith(f"{kind}/")
        & (rounds["status"] == STATUS_OK)
        & (rounds["planner"] == planner)
    ]
    rows = []
    for r in done.itertuples():
        g = by_key.get(r.trial_key)
        outcomes = [] if g is None else [str(o) for o in g["outcome"]]
        wins = [] if g is None else list(g["success"].to_numpy(dtype=float) > 0)
        rk, rn, rcut = vgn_round(outcomes, wins)
        rows.append(
            {
                "draw": (r.base_seed, r.trial_index),
                "objects": r.objects,
                "vgn_k": rk,
                "vgn_n": rn,
                "cut": int(rcut),
                "our_k": int(sum(wins)),
                "our_n": len(wins),
                "presented": int(r.n_objects),
                "cleared": int(r.n_cleared),
            }
        )
    columns = ["draw", "objects", "vgn_k", "vgn_n", "cut", "our_k", "our_n", "presented",
               "cleared"]  # fmt: skip
    return pd.DataFrame(rows, columns=columns).set_index("draw")


def _over_rounds(k: pd.Series, n: pd.Series, confidence: float) -> tuple[float, float]:
    """The interval over rounds of sum(k) / sum(n), percent."""
    low, high = rate_over_clusters(k.to_numpy(), n.to_numpy(), confidence)
    return 100 * low, 100 * high


def _vs_reference(mine: pd.DataFrame, ref: pd.DataFrame, confidence: float) -> dict[str, float]:
    """Declutter rate minus the reference's over the rounds both ran on the same draw."""
    common = [i for i in mine.index.intersection(ref.index)
              if mine.at[i, "objects"] == ref.at[i, "objects"]]  # fmt: skip
    if not common:
        return {"dr_vs_reference_pp": np.nan, "dr_vs_reference_p": np.nan}
    a, b = mine.loc[common], ref.loc[common]
    c = ClusterDifference.of(a["vgn_k"], a["presented"], b["vgn_k"], b["presented"], confidence)
    return {
        "dr_vs_reference_pp": 100 * c.difference,
        "dr_vs_reference_low_pp": 100 * c.low,
        "dr_vs_reference_high_pp": 100 * c.high,
        "dr_vs_reference_rounds": c.clusters,
        "dr_vs_reference_p": c.p_value,
    }


def clutter_table(data: RunData, reference: str = "hsq") -> pd.DataFrame:
    """One row per round kind and planner: VGN-rule GSR and GIGA's declutter rate with
    intervals over rounds, VGN's ``percent_cleared``, our GSR and CR of the same rounds, and
    the declutter rate's paired difference to ``reference`` over rounds (Holm-adjusted over
    the planners of a kind)."""
    attempts, rounds = data.attempts, data.rounds
    rows: list[dict[str, Any]] = []
    if rounds.empty:
        return pd.DataFrame()
    ok = attempts[attempts["status"] == STATUS_OK]
    by_key = {k: g.sort_values("attempt_index") for k, g in ok.groupby("trial_key")}
    for kind in KINDS:
        per = {p: _rounds(data, kind, p, by_key) for p in data.planners}
        kind_rows = []
        for p in data.planners:
            mine = per[p]
            if mine.empty:
                continue
            k, n, presented = mine["vgn_k"].sum(), mine["vgn_n"].sum(), mine["presented"].sum()
            logged = mine.loc[mine["vgn_n"] > 0, "presented"].sum()
            gsr_low, gsr_high = _over_rounds(mine["vgn_k"], mine["vgn_n"], data.confidence)
            dr_low, dr_high = _over_rounds(mine["vgn_k"], mine["presented"], data.confidence)
            ref = per.get(reference, pd.DataFrame())
            paired = {} if p == reference or ref.empty else _vs_reference(mine, ref,
                                                                          data.confidence)  # fmt: skip
            kind_rows.append(
                {
                    "experiment": kind,
                    "planner": p,
                    "rounds": len(mine),
                    "rounds_cut": int(mine["cut"].sum()),
                    "vgn_successes": int(k),
                    "vgn_attempts": int(n),
                    "vgn_gsr_percent": 100 * k / n if n else np.nan,
                    "vgn_gsr_low_percent": gsr_low,
                    "vgn_gsr_high_percent": gsr_high,
                    "declutter_percent": 100 * k / presented,
                    "declutter_low_percent": dr_low,
                    "declutter_high_percent": dr_high,
                    "vgn_percent_cleared": 100 * k / logged if logged else np.nan,
                    "objects_presented": int(presented),
                    "our_gsr_percent": 100 * mine["our_k"].sum() / mine["our_n"].sum()
                    if mine["our_n"].sum()
                    else np.nan,
                    "our_cr_percent": 100 * mine["cleared"].sum() / presented,
                    **paired,
                }
            )
        table = pd.DataFrame(kind_rows)
        if "dr_vs_reference_p" in table:
            table["dr_vs_reference_p_holm"], table["dr_vs_reference_verdict"] = holm_verdicts(
                table["dr_vs_reference_pp"].to_numpy(),
                table["dr_vs_reference_p"].to_numpy(),
                data.confidence,
            )
        rows += table.to_dict("records")
    return pd.DataFrame(rows)


def _vs(r: pd.Series) -> str:
    p = r.get("dr_vs_reference_p_holm", np.nan)
    if p is None or not np.isfinite(p):
        return "—"
    low = r.get("dr_vs_reference_low_pp", np.nan)
    ci = (
        f" [{signed_pp(low)}, {signed_pp(r['dr_vs_reference_high_pp'])}]"
        if np.isfinite(low)
        else ""
    )
    return (
        f"{signed_pp(r['dr_vs_reference_pp'])}{ci}, p {p_text(p)}, {r['dr_vs_reference_verdict']}"
    )


def render_clutter(data: RunData, table: pd.DataFrame, reference: str = "hsq") -> list[str]:
    """Markdown lines of the VGN/GIGA-comparable section (none without packed or pile rounds)."""
    if table.empty:
        return []
    conf = f"{100 * data.confidence:g} %"
    out = [
        "## Clutter metrics as VGN and GIGA count them",
        "",
        "The same rounds, counted as VGN and GIGA count theirs: a round also ends at the first "
        "attempt without a grasp, which is not an attempt. Declutter rate: GIGA's "
        "`declutter_rate` = successful grasps / objects presented in all rounds; VGN's "
        "`percent_cleared` divides by the objects of the rounds that logged at least one grasp "
        "only, so it is higher when a round ends before its first grasp. Set these beside their "
        "papers' GSR and DR, not ours. Rounds cut: rounds that end earlier under their rule.",
        "",
    ]
    heads = ["experiment", "planner", "GSR (VGN rule)", f"{conf} CI", "k/n",
             "declutter rate (GIGA)", f"{conf} CI", "percent_cleared (VGN)", "our GSR", "our CR",
             "rounds cut", f"declutter rate vs {reference} (pp) [CI], p Holm"]  # fmt: skip
    out += ["| " + " | ".join(heads) + " |", "|" + "|".join(" --- " for _ in heads) + "|"]
    for _, r in table.iterrows():
        gsr_ok = np.isfinite(r["vgn_gsr_percent"])
        cells = [
            str(r["experiment"]),
            method_label(r["planner"]),
            f"{r['vgn_gsr_percent']:.1f}" if gsr_ok else "—",
            _ci(r["vgn_gsr_low_percent"], r["vgn_gsr_high_percent"]),
            f"{int(r['vgn_successes'])}/{int(r['vgn_attempts'])}",
            f"{r['declutter_percent']:.1f}",
            _ci(r["declutter_low_percent"], r["declutter_high_percent"]),
            f"{r['vgn_percent_cleared']:.1f}" if np.isfinite(r["vgn_percent_cleared"]) else "—",
            f"{r['our_gsr_percent']:.1f}" if np.isfinite(r["our_gsr_percent"]) else "—",
            f"{r['our_cr_percent']:.1f}",
            f"{int(r['rounds_cut'])}/{int(r['rounds'])}",
            _vs(r) if r["planner"] != reference else "reference",
        ]
        out.append("| " + " | ".join(cells) + " |")
    out += [
        "",
        f"Intervals over rounds (cluster bootstrap, {N_RESAMPLES:,} resamples): the objects and "
        "grasps of one round are not independent. Declutter rate vs the reference: the same "
        "draws, exact sign-flip test over rounds, p adjusted by Holm's method over the planners "
        "of each experiment; the verdict follows the adjusted p. See docs/statistics.md.",
        "",
    ]
    return out


def _ci(low: float, high: float) -> str:
    return "—" if not np.isfinite(low) else f"[{low:.1f}, {high:.1f}]"


def rates_over_rounds(ok: pd.DataFrame, rounds: pd.DataFrame, confidence: float) -> dict:
    """GSR and CR intervals over rounds (``gsr_ci_*``, ``cr_ci_*``, percent) from one
    planner's attempts and finished rounds of one kind: the objects and grasps of a round share
    a scene and a sequence, so the round is the independent unit (NaN under five rounds)."""
    key = ["base_seed", "trial_index"]
    if len(ok):
        per = ok.groupby(key)["success"].agg(["sum", "count"])
        gsr = rate_over_clusters(per["sum"].to_numpy(), per["count"].to_numpy(), confidence)
    else:
        gsr = (np.nan, np.nan)
    cr = (
        rate_over_clusters(
            rounds["n_cleared"].to_numpy(), rounds["n_objects"].to_numpy(), confidence
        )
        if len(rounds)
        else (np.nan, np.nan)
    )
    return {
        "gsr_ci_low_percent": 100 * gsr[0],
        "gsr_ci_high_percent": 100 * gsr[1],
        "cr_ci_low_percent": 100 * cr[0],
        "cr_ci_high_percent": 100 * cr[1],
    }
