"""Two runs of one protocol compared trial by trial (``hsqbench compare RUN_A RUN_B``).

Trial seeds derive from (base seed, experiment, object, index) alone, so the same trial key in
two runs presents the same pose or draw: a change of code or config shows as attempts whose
recorded columns differ. Per planner, the isolated attempts pair up (success in A, in B) and the
packed and pile rounds' objects pair up (removed in A, in B), so B - A is a paired difference
(:mod:`hsqbench.experiment.paired`): "worse" means B lost significantly more pairs than it won,
by the p-value Holm-adjusted over all of compare's tests. Rounds are the units of the CR test
(objects of one round are not independent).
"""

from __future__ import annotations

from collections import Counter
from typing import Any

import pandas as pd

from hsqbench.experiment.holm import holm_verdicts
from hsqbench.experiment.paired import WORSE, PairedDifference
from hsqbench.experiment.paired_table import clustered, finished_rounds, object_pairs
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.rows import ATTEMPT_COLUMNS, VOLATILE_COLUMNS
from hsqbench.experiment.run_data import RunData

#: Columns that need not match for the same trial: the machine's and the moment's (timings,
#: the worker, versions; rows.VOLATILE_COLUMNS) and the config hash (a run differs by config).
UNFIXED = frozenset(VOLATILE_COLUMNS) | {"config_hash"}
KEY = ("trial_key", "attempt_index")
#: Columns that must match for the same trial (the seeds fix them): every other column.
MATCH = tuple(c for c in ATTEMPT_COLUMNS if c not in UNFIXED | set(KEY))


def matched_attempts(a: RunData, b: RunData) -> pd.DataFrame:
    """The attempts of both runs side by side (columns ``<name>_a``, ``<name>_b``), joined on
    the trial key and attempt index; ``_merge`` says ``both``, ``left_only`` or ``right_only``."""
    return pd.merge(
        a.attempts, b.attempts, on=list(KEY), how="outer", suffixes=("_a", "_b"), indicator=True
    ).sort_values(list(KEY), kind="stable")


def changed_attempts(merged: pd.DataFrame, columns: tuple[str, ...]) -> list[tuple[tuple, list]]:
    """((trial key, attempt index), columns that differ) of the attempts in both runs."""
    both = merged[merged["_merge"] == "both"]
    present = [c for c in columns if f"{c}_a" in both and f"{c}_b" in both]
    differs = pd.DataFrame({c: _differ(both[f"{c}_a"], both[f"{c}_b"]) for c in present})
    out = []
    for i in differs.index[differs.any(axis=1)] if len(differs.columns) else []:
        key = (both.at[i, "trial_key"], both.at[i, "attempt_index"])
        out.append((key, [c for c in present if differs.at[i, c]]))
    return out


def _differ(x: pd.Series, y: pd.Series) -> pd.Series:
    """Where two columns differ: numbers by value (an outer join makes integers floats),
    the rest as text; two missing values are equal."""
    if pd.api.types.is_numeric_dtype(x) and pd.api.types.is_numeric_dtype(y):
        return ~((x == y) | (x.isna() & y.isna()))
    return x.fillna("").astype(str) != y.fillna("").astype(str)


def outcome_transitions(merged: pd.DataFrame) -> Counter:
    """(outcome in A, outcome in B) -> attempts, over the attempts in both runs."""
    both = merged[merged["_merge"] == "both"]
    return Counter(zip(both["outcome_a"].astype(str), both["outcome_b"].astype(str), strict=True))


def isolated_pairs(merged: pd.DataFrame) -> pd.DataFrame:
    """Columns ``planner``, ``object``, ``a``, ``b`` (success): isolated attempts both runs
    recorded without an infrastructure error."""
    both = merged[merged["_merge"] == "both"]
    ok = both[
        (both["experiment_a"] == "isolated")
        & (both["status_a"] == STATUS_OK)
        & (both["status_b"] == STATUS_OK)
    ]
    return pd.DataFrame(
        {
            "planner": ok["planner_a"].astype(str),
            "object": ok["objects_a"].astype(str),
            "a": ok["success_a"].to_numpy(dtype=float) > 0,
            "b": ok["success_b"].to_numpy(dtype=float) > 0,
        }
    )


def _row(comparison: str, planner: str, a_percent: float, b_percent: float, lost: int, won: int,
         pairs: int) -> dict[str, Any]:  # fmt: skip
    return {
        "comparison": comparison,
        "planner": planner,
        "pairs": pairs,
        "a_percent": a_percent,
        "b_percent": b_percent,
        "success_to_failure": lost,
        "failure_to_success": won,
    }


def run_differences(a: RunData, b: RunData, merged: pd.DataFrame) -> pd.DataFrame:
    """B - A per planner: isolated GSR over paired attempts (Newcombe, exact McNemar: the
    question is these presentations), packed and pile CR over paired rounds (the same trial
    key, the same draw; bootstrap interval and exact sign-flip test over rounds, since the
    objects of a round are not independent). p Holm-adjusted over all of them, and the verdicts
    follow the adjusted p."""
    rows = _isolated_rows(merged, a.confidence)
    for kind in ("packed", "pile"):
        rows += _round_rows(a, b, kind)
    table = pd.DataFrame(rows)
    if table.empty:
        return table
    table["p_holm"], table["verdict"] = holm_verdicts(
        table["difference_pp"].to_numpy(), table["p_value"].to_numpy(), a.confidence
    )
    return table


def _isolated_rows(merged: pd.DataFrame, confidence: float) -> list[dict[str, Any]]:
    """One row per planner: isolated GSR, B - A over the paired attempts."""
    rows = []
    iso = isolated_pairs(merged)
    for planner, sub in iso.groupby("planner", sort=False):
        d = PairedDifference.of(sub["b"], sub["a"], confidence)  # B is "the planner"
        rows.append(
            {
                **_row(
                    "isolated GSR",
                    str(planner),
                    100 * (d.both + d.only_reference) / d.n,
                    100 * (d.both + d.only_planner) / d.n,
                    d.only_reference,
                    d.only_planner,
                    d.n,
                ),
                "over": "presentations",
                "difference_pp": 100 * d.difference,
                "ci_low_pp": 100 * d.low,
                "ci_high_pp": 100 * d.high,
                "p_value": d.p_value,
            }
        )
    return rows


def _round_rows(a: RunData, b: RunData, kind: str) -> list[dict[str, Any]]:
    """One row per planner with paired rounds: ``kind`` (packed, pile) CR, B - A over the
    rounds both runs finished."""
    ra, rb = finished_rounds(a.rounds, kind), finished_rounds(b.rounds, kind)
    if ra.empty or rb.empty:
        return []
    rows = []
    for planner in dict.fromkeys(ra["planner"]):
        pairs = object_pairs(  # its "planner" column is run A's, "reference" run B's
            ra[ra["planner"] == planner].set_index("trial_key"),
            rb[rb["planner"] == planner].set_index("trial_key"),
        )
        if not len(pairs):
            continue
        ab = pairs.rename(columns={"planner": "reference", "reference": "planner"})
        c = clustered(ab, "round", a.confidence)
        won = int((ab["planner"] & ~ab["reference"]).sum())
        lost = int((~ab["planner"] & ab["reference"]).sum())
        rows.append(
            {
                **_row(
                    f"{kind} CR",
                    str(planner),
                    100 * ab["reference"].mean(),
                    100 * ab["planner"].mean(),
                    lost,
                    won,
                    len(ab),
                ),
                "over": f"{c.clusters} rounds",
                "difference_pp": 100 * c.difference,
                "ci_low_pp": 100 * c.low,
                "ci_high_pp": 100 * c.high,
                "p_value": c.p_value,
            }
        )
    return rows


def object_transitions(merged: pd.DataFrame) -> pd.DataFrame:
    """Isolated attempts per planner and object that changed: success -> failure (lost) and
    failure -> success (won), of the pairs; objects without a change are left out."""
    iso = isolated_pairs(merged)
    iso = iso.assign(lost=iso["a"] & ~iso["b"], won=~iso["a"] & iso["b"], pairs=1)
    per = iso.groupby(["planner", "object"], sort=False)[["lost", "won", "pairs"]].sum()
    return per[(per["lost"] > 0) | (per["won"] > 0)].reset_index()


def worse(differences: pd.DataFrame) -> pd.DataFrame:
    """The rows where B is significantly worse than A."""
    if differences.empty:
        return differences
    return differences[differences["verdict"] == WORSE]
