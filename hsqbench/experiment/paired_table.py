"""The paired section of a report: each planner against a reference planner (hsq by default) on
the presentations both ran (statistics in :mod:`hsqbench.experiment.paired`).

- Isolated GSR: pairs are presentations (base seed, object, pose index); the primary interval
  and test are over objects (:mod:`hsqbench.experiment.over_clusters`), beside Newcombe's
  interval and McNemar's test over the presentations (:mod:`hsqbench.experiment.paired`).
- Packed and pile CR: pairs are the objects of a round (removed or not, by each planner); the
  interval and test are over rounds only, since objects of one round are not independent.
- Packed and pile GSR: a round (the same draw) is the pair; each planner makes its own attempts
  in it, so only the rounds pair up.
- p-values are Holm-adjusted within each comparison (:mod:`hsqbench.experiment.holm`).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.cluster import N_RESAMPLES
from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.holm import holm_verdicts
from hsqbench.experiment.markdown import md_table, p_text
from hsqbench.experiment.over_clusters import ClusterDifference
from hsqbench.experiment.paired import PairedDifference
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.sign_flip import N_DRAWS

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


def round_gsr_counts(data: RunData, kind: str, planner: str, reference: str) -> pd.DataFrame:
    """Per ``kind`` round both planners finished on the same draw: each one's successes and
    attempts in it (columns ``k_planner``, ``n_planner``, ``k_reference``, ``n_reference``)."""
    key = ["base_seed", "trial_index"]
    ok_rounds = finished_rounds(data.rounds, kind)
    att = data.attempts
    if ok_rounds.empty or att.empty:
        return pd.DataFrame(columns=["k_planner", "n_planner", "k_reference", "n_reference"])
    att = att[(att["experiment"] == kind) & (att["status"] == STATUS_OK)]
    per_round = att.groupby(["planner", *key])["success"].agg(["sum", "count"])
    mine = ok_rounds[ok_rounds["planner"] == planner].set_index(key)
    ref = ok_rounds[ok_rounds["planner"] == reference].set_index(key)
    rows = []
    for idx in mine.index.intersection(ref.index):
        if mine.loc[idx, "objects"] != ref.loc[idx, "objects"]:  # another draw: not a pair
            continue
        a, b = (planner, *idx), (reference, *idx)
        ka, na = per_round.loc[a] if a in per_round.index else (0, 0)
        kb, nb = per_round.loc[b] if b in per_round.index else (0, 0)
        rows.append({"k_planner": ka, "n_planner": na, "k_reference": kb, "n_reference": nb})
    return pd.DataFrame(rows, columns=["k_planner", "n_planner", "k_reference", "n_reference"])


def clustered(pairs: pd.DataFrame, cluster: str, confidence: float) -> ClusterDifference:
    """The paired difference of ``pairs`` (columns ``planner``, ``reference``, ``cluster``)
    over its clusters: bootstrap interval and exact sign-flip test."""
    sums = (
        pd.DataFrame(
            {
                "c": pairs[cluster],
                "k_planner": pairs["planner"].astype(int),
                "k_reference": pairs["reference"].astype(int),
                "n": 1,
            }
        )
        .groupby("c", sort=False)
        .sum()
    )
    return ClusterDifference.of(
        sums["k_planner"], sums["n"], sums["k_reference"], sums["n"], confidence
    )


def _pairs_row(comparison: str, planner: str, reference: str, pairs: pd.DataFrame, cluster: str,
               confidence: float) -> dict[str, Any]:  # fmt: skip
    """A paired row: primary over clusters; for isolated GSR also over the presentations."""
    d = PairedDifference.of(pairs["planner"].to_numpy(), pairs["reference"].to_numpy(), confidence)
    c = clustered(pairs, cluster, confidence)
    # Objects of one round are not independent: no per-object test of CR.
    per_presentation = comparison == "isolated GSR"
    return {
        **_base(comparison, planner, reference, cluster, c),
        "pairs": d.n,
        "both": d.both,
        "only_planner": d.only_planner,
        "only_reference": d.only_reference,
        "neither": d.neither,
        "planner_successes": d.both + d.only_planner,
        "planner_attempts": d.n,
        "reference_successes": d.both + d.only_reference,
        "reference_attempts": d.n,
        "presentations_ci_low_pp": 100 * d.low if per_presentation else np.nan,
        "presentations_ci_high_pp": 100 * d.high if per_presentation else np.nan,
        "presentations_p_value": d.p_value if per_presentation else np.nan,
    }


def _gsr_row(comparison: str, planner: str, reference: str, counts: pd.DataFrame,
             confidence: float) -> dict[str, Any]:  # fmt: skip
    """A round-level GSR row: each planner's own attempts in the same rounds."""
    c = ClusterDifference.of(counts["k_planner"], counts["n_planner"], counts["k_reference"],
                             counts["n_reference"], confidence)  # fmt: skip
    return {
        **_base(comparison, planner, reference, "round", c),
        "planner_successes": int(counts["k_planner"].sum()),
        "planner_attempts": int(counts["n_planner"].sum()),
        "reference_successes": int(counts["k_reference"].sum()),
        "reference_attempts": int(counts["n_reference"].sum()),
    }


def _base(comparison: str, planner: str, reference: str, cluster: str,
          c: ClusterDifference) -> dict[str, Any]:  # fmt: skip
    return {
        "comparison": comparison,
        "planner": planner,
        "reference": reference,
        "unit": cluster + "s",
        "clusters": c.clusters,
        "difference_pp": 100 * c.difference,
        "ci_low_pp": 100 * c.low,
        "ci_high_pp": 100 * c.high,
        "p_value": c.p_value,
    }


def judge(table: pd.DataFrame, confidence: float) -> pd.DataFrame:
    """``table`` with Holm-adjusted p and verdicts, one family per comparison (the planners of
    one table), for the tests over clusters and, where present, over presentations."""
    table = table.copy()
    for prefix in ("", "presentations_"):
        if f"{prefix}p_value" not in table:
            table[f"{prefix}p_value"] = np.nan
        table[f"{prefix}p_holm"] = np.nan
        table[f"{prefix}verdict"] = "—"
        for _, idx in table.groupby("comparison", sort=False).groups.items():
            diff = table.loc[idx, "difference_pp"].to_numpy()
            adjusted, words = holm_verdicts(diff, table.loc[idx, f"{prefix}p_value"], confidence)
            table.loc[idx, f"{prefix}p_holm"] = adjusted
            table.loc[idx, f"{prefix}verdict"] = words
    return table


def paired_table(data: RunData, reference: str = DEFAULT_REFERENCE) -> pd.DataFrame:
    """One row per planner (not the reference) and comparison it has pairs in: isolated GSR
    over objects, packed and pile CR and GSR over rounds; verdicts Holm-adjusted per comparison."""
    rows = []
    conf = data.confidence
    for p in (p for p in data.planners if p != reference):
        iso = isolated_pairs(data, p, reference)
        if len(iso):
            rows.append(_pairs_row("isolated GSR", p, reference, iso, "object", conf))
        for kind in _ROUND_KINDS:
            objs = round_pairs(data, kind, p, reference)
            if len(objs):
                rows.append(_pairs_row(f"{kind} CR", p, reference, objs, "round", conf))
            counts = round_gsr_counts(data, kind, p, reference)
            if len(counts) and counts["n_planner"].sum() and counts["n_reference"].sum():
                rows.append(_gsr_row(f"{kind} GSR", p, reference, counts, conf))
    return judge(pd.DataFrame(rows), conf) if rows else pd.DataFrame()


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


def _counts(r: pd.Series) -> str:
    """won:lost of the pairs, or (GSR of rounds) each planner's successes/attempts."""
    if np.isfinite(r.get("pairs", np.nan)):
        return f"{int(r['only_planner'])}:{int(r['only_reference'])} of {int(r['pairs'])}"
    return (
        f"{int(r['planner_successes'])}/{int(r['planner_attempts'])} vs "
        f"{int(r['reference_successes'])}/{int(r['reference_attempts'])}"
    )


def _presentations(r: pd.Series) -> str:
    if not np.isfinite(r.get("presentations_p_value", np.nan)):
        return "—"
    return (
        f"[{_pp(r['presentations_ci_low_pp'])}, {_pp(r['presentations_ci_high_pp'])}], "
        f"p {p_text(r['presentations_p_holm'])}, {r['presentations_verdict']}"
    )


def paired_note(data: RunData, table: pd.DataFrame) -> str:
    """The line under the paired table: units, tests, and the Holm families."""
    conf = f"{100 * data.confidence:g} %"
    families = table.groupby("comparison", sort=False).size()
    sizes = ", ".join(f"{n} in {c}" for c, n in families.items())
    return (
        f"Difference = planner − reference, percentage points. Over objects (isolated GSR) or "
        f"rounds (packed and pile CR and GSR): the {conf} cluster-bootstrap interval (BCa, "
        f"{N_RESAMPLES:,} resamples) and a paired sign-flip test over those clusters (exact; GSR "
        f"of rounds, whose attempts differ per planner: a swap permutation test, exact up to "
        f"{N_DRAWS:,} patterns, else {N_DRAWS:,} draws, fixed seed). p Holm: p adjusted by "
        f"Holm's method within each comparison (the rows of one table: {sizes}); the verdicts "
        f"follow the adjusted p (< {1 - data.confidence:.2g}). On these presentations "
        "(isolated): Newcombe's paired interval and the exact McNemar test, Holm-adjusted in the "
        "same families, a claim about these poses of these objects only. See docs/statistics.md."
    )


def render_paired(data: RunData, table: pd.DataFrame, per_object: pd.DataFrame,
                  reference: str) -> list[str]:  # fmt: skip
    """Markdown lines of the paired section (a one-line note when there is nothing to pair)."""
    conf = f"{100 * data.confidence:g} %"
    out = [f"## Paired comparison with {method_label(reference)} (same presentations)", ""]
    if reference not in data.planners:
        return [*out, f"The reference planner {reference} did not run here: nothing to pair.", ""]
    if table.empty:
        return [*out, "No other planner ran the same presentations: nothing to pair.", ""]
    heads = ["comparison", "planner vs reference", "difference", f"{conf} CI", "over",
             "won:lost (pairs) or k/n", "p", "p Holm", "verdict",
             f"on these presentations: {conf} CI, p Holm, verdict"]  # fmt: skip
    rows = [
        [
            r["comparison"],
            f"{method_label(r['planner'])} vs {reference}",
            _pp(r["difference_pp"]),
            f"[{_pp(r['ci_low_pp'])}, {_pp(r['ci_high_pp'])}]",
            f"{int(r['clusters'])} {r['unit']}",
            _counts(r),
            p_text(r["p_value"]),
            p_text(r["p_holm"]),
            f"**{r['verdict']}**",
            _presentations(r),
        ]
        for _, r in table.iterrows()
    ]
    out += [md_table(heads, rows), "", paired_note(data, table), ""]
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
