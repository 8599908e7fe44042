"""The paired section of a report: each planner against a reference planner (hsq by default) on
the presentations both ran (statistics in :mod:`hsqbench.experiment.paired`).

- Isolated GSR: pairs are presentations (base seed, object, pose index); the interval over
  objects resamples objects (:mod:`hsqbench.experiment.cluster`).
- Packed and pile CR: pairs are the objects of a round (removed or not, by each planner); the
  interval over rounds resamples rounds, since objects of one round are not independent.
- Packed GSR is not paired: after the first attempt the planners face different scenes.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.cluster import MIN_CLUSTERS, cluster_interval
from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.markdown import md_table
from hsqbench.experiment.paired import BETTER, SAME, WORSE, PairedDifference
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData

PAIRED_CSV = "paired.csv"
PAIRED_OBJECTS_CSV = "paired_per_object.csv"
DEFAULT_REFERENCE = "hsq"
_ROUND_KINDS = ("packed", "pile")


def isolated_pairs(data: RunData, planner: str, reference: str) -> pd.DataFrame:
    """Columns ``object``, ``planner``, ``reference`` (successes as bool), one row per
    isolated presentation both planners ran without an infrastructure error."""
    df = data.attempts
    if df.empty:
        return pd.DataFrame(columns=["object", "planner", "reference"])
    ok = df[(df["experiment"] == "isolated") & (df["status"] == STATUS_OK)]
    key = ["base_seed", "objects", "trial_index", "attempt_index"]
    mine = ok[ok["planner"] == planner].set_index(key)["success"]
    ref = ok[ok["planner"] == reference].set_index(key)["success"]
    both = pd.concat({"planner": mine, "reference": ref}, axis=1, join="inner").reset_index()
    both = both.sort_values(key, kind="stable")
    return pd.DataFrame(
        {
            "object": both["objects"].astype(str).to_numpy(),
            "planner": both["planner"].to_numpy(dtype=float) > 0,
            "reference": both["reference"].to_numpy(dtype=float) > 0,
        }
    )


def round_pairs(data: RunData, kind: str, planner: str, reference: str) -> pd.DataFrame:
    """Columns ``round``, ``object``, ``planner``, ``reference`` (removed, bool): one row per
    object of each ``kind`` round both planners finished on the same draw."""
    ok = finished_rounds(data.rounds, kind)
    key = ["base_seed", "trial_index"]
    return object_pairs(
        ok[ok["planner"] == planner].set_index(key), ok[ok["planner"] == reference].set_index(key)
    )


def finished_rounds(rounds: pd.DataFrame, kind: str) -> pd.DataFrame:
    """The ``kind`` (packed, pile) rounds that finished without an infrastructure error."""
    if rounds.empty:
        return rounds
    return rounds[rounds["trial_key"].str.startswith(f"{kind}/") & (rounds["status"] == STATUS_OK)]


def object_pairs(mine: pd.DataFrame, ref: pd.DataFrame) -> pd.DataFrame:
    """Per object of the rounds in both frames (indexed alike, one round a row) on the same
    draw: removed by ``mine``'s planner, by ``ref``'s (columns ``round``, ``object``,
    ``planner``, ``reference``)."""
    rows: list[dict[str, Any]] = []
    for idx in mine.index.intersection(ref.index):
        a, b = mine.loc[idx], ref.loc[idx]
        if a["objects"] != b["objects"]:  # another draw: not a pair
            continue
        cleared_a = set(str(a["objects_cleared"]).split(";"))
        cleared_b = set(str(b["objects_cleared"]).split(";"))
        for obj in str(a["objects"]).split(";"):
            rows.append(
                {
                    "round": str(idx),
                    "object": obj,
                    "planner": obj in cleared_a,
                    "reference": obj in cleared_b,
                }
            )
    return pd.DataFrame(rows, columns=["round", "object", "planner", "reference"])


def _over(pairs: pd.DataFrame, cluster: str, confidence: float) -> tuple[float, float]:
    """The paired difference's interval resampling ``cluster`` (NaN with too few clusters)."""
    won = (pairs["planner"] & ~pairs["reference"]).astype(int)
    lost = (~pairs["planner"] & pairs["reference"]).astype(int)
    grouped = pd.DataFrame({"c": pairs[cluster], "d": won - lost, "n": 1}).groupby("c")
    sums = grouped.sum()
    if len(sums) < MIN_CLUSTERS:
        return np.nan, np.nan
    return cluster_interval(sums["d"].to_numpy(), sums["n"].to_numpy(), confidence)


def _verdict(low: float, high: float) -> str:
    if not np.isfinite(low):
        return "—"
    return BETTER if low > 0 else WORSE if high < 0 else SAME


def _row(comparison: str, planner: str, reference: str, pairs: pd.DataFrame, cluster: str,
         confidence: float) -> dict[str, Any]:  # fmt: skip
    d = PairedDifference.of(pairs["planner"].to_numpy(), pairs["reference"].to_numpy(), confidence)
    low, high = _over(pairs, cluster, confidence)
    return {
        "comparison": comparison,
        "planner": planner,
        "reference": reference,
        "pairs": d.n,
        "both": d.both,
        "only_planner": d.only_planner,
        "only_reference": d.only_reference,
        "neither": d.neither,
        **d.summary_columns(),
        "clusters": cluster + "s",
        "cluster_ci_low_pp": 100 * low,
        "cluster_ci_high_pp": 100 * high,
        "cluster_verdict": _verdict(low, high),
    }


def paired_table(data: RunData, reference: str = DEFAULT_REFERENCE) -> pd.DataFrame:
    """One row per planner (not the reference) and comparison it has pairs in."""
    rows = []
    for p in (p for p in data.planners if p != reference):
        iso = isolated_pairs(data, p, reference)
        if len(iso):
            rows.append(_row("isolated GSR", p, reference, iso, "object", data.confidence))
        for kind in _ROUND_KINDS:
            objs = round_pairs(data, kind, p, reference)
            if len(objs):
                rows.append(_row(f"{kind} CR", p, reference, objs, "round", data.confidence))
    return pd.DataFrame(rows)


def paired_per_object(data: RunData, reference: str = DEFAULT_REFERENCE) -> pd.DataFrame:
    """Isolated GSR difference to the reference per object and planner (no correction for the
    many tests: a per-object p-value below 0.05 is expected by chance among 39 objects)."""
    rows = []
    for p in (p for p in data.planners if p != reference):
        iso = isolated_pairs(data, p, reference)
        for obj in (o for o in data.objects if (iso["object"] == o).any()):
            sub = iso[iso["object"] == obj]
            d = PairedDifference.of(sub["planner"].to_numpy(), sub["reference"].to_numpy(),
                                    data.confidence)  # fmt: skip
            rows.append(
                {
                    "object": obj,
                    "planner": p,
                    "reference": reference,
                    "pairs": d.n,
                    "only_planner": d.only_planner,
                    "only_reference": d.only_reference,
                    "difference_pp": 100 * d.difference,
                    "ci_low_pp": 100 * d.low,
                    "ci_high_pp": 100 * d.high,
                    "p_value": d.p_value,
                }
            )
    return pd.DataFrame(rows)


def _pp(v: float) -> str:
    return "—" if not np.isfinite(v) else f"{v:+.1f}"


def render_paired(data: RunData, table: pd.DataFrame, per_object: pd.DataFrame,
                  reference: str) -> list[str]:  # fmt: skip
    """Markdown lines of the paired section (a one-line note when there is nothing to pair)."""
    conf = f"{100 * data.confidence:g} %"
    out = [f"## Paired comparison with {method_label(reference)} (same presentations)", ""]
    if reference not in data.planners:
        return [*out, f"The reference planner {reference} did not run here: nothing to pair.", ""]
    if table.empty:
        return [*out, "No other planner ran the same presentations: nothing to pair.", ""]
    out += [
        f"Difference = planner − {reference}, percentage points, over the presentations both "
        f"ran. CI: Newcombe's paired score interval ({conf}); p: exact McNemar test on the "
        "discordant pairs (won:lost). Verdict: better or worse when p < "
        f"{1 - data.confidence:.2g}. Over objects/rounds: the {conf} cluster-bootstrap interval "
        "and its verdict, the claim about new objects (or rounds). See docs/statistics.md.",
        "",
    ]
    heads = ["comparison", "planner vs reference", "difference", f"{conf} CI", "won:lost",
             "pairs", "p (McNemar)", "verdict", "over objects/rounds", "verdict over them"]  # fmt: skip
    rows = [
        [
            r["comparison"],
            f"{method_label(r['planner'])} vs {reference}",
            _pp(r["difference_pp"]),
            f"[{_pp(r['ci_low_pp'])}, {_pp(r['ci_high_pp'])}]",
            f"{int(r['only_planner'])}:{int(r['only_reference'])}",
            str(int(r["pairs"])),
            f"{r['p_value']:.3g}",
            f"**{r['verdict']}**",
            f"[{_pp(r['cluster_ci_low_pp'])}, {_pp(r['cluster_ci_high_pp'])}] ({r['clusters']})",
            str(r["cluster_verdict"]),
        ]
        for _, r in table.iterrows()
    ]
    out += [md_table(heads, rows), ""]
    if not per_object.empty:
        out += _per_object(per_object, reference)
    return out


def _per_object(per_object: pd.DataFrame, reference: str) -> list[str]:
    planners = list(dict.fromkeys(per_object["planner"]))
    out = [f"### Isolated GSR difference to {reference} per object (pp, won:lost, p)", "",
           "Not corrected for the number of objects: read it for where a difference comes from.",
           ""]  # fmt: skip
    rows = []
    for obj, sub in per_object.groupby("object", sort=False):
        cells = [str(obj)]
        by = sub.set_index("planner")
        for p in planners:
            r = by.loc[p] if p in by.index else None
            cells.append(
                "—"
                if r is None
                else f"{_pp(r['difference_pp'])} ({int(r['only_planner'])}:"
                f"{int(r['only_reference'])}, {r['p_value']:.2g})"
            )
        rows.append(cells)
    return [*out, md_table(["object", *(f"{p} − {reference}" for p in planners)], rows), ""]
