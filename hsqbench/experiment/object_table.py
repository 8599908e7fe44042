"""Object-level uncertainty of isolated GSR (the unseen-object claim): per planner, the
per-attempt Wilson interval beside the cluster-bootstrap interval over objects, and the spread
of per-object GSRs (objects under 50 %, the worst five); :mod:`hsqbench.experiment.cluster`."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.cluster import MIN_CLUSTERS, ObjectSpread, cluster_interval
from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.stats import Rate

OBJECTS_CSV = "object_level.csv"


def object_level(data: RunData) -> pd.DataFrame:
    """One row per planner with isolated attempts on at least :data:`MIN_CLUSTERS` objects."""
    df = data.attempts
    if df.empty:
        return pd.DataFrame()
    ok = df[(df["experiment"] == "isolated") & (df["status"] == STATUS_OK)]
    rows: list[dict[str, Any]] = []
    for p in data.planners:
        mine = ok[ok["planner"] == p]
        per = mine.groupby("objects", sort=False)["success"].agg(["sum", "count"])
        if len(per) < MIN_CLUSTERS:
            continue
        k, n = per["sum"].to_numpy(dtype=int), per["count"].to_numpy(dtype=int)
        rate = Rate.of(int(k.sum()), int(n.sum()), data.confidence)
        low, high = cluster_interval(k, n, data.confidence)
        spread = ObjectSpread.of(
            pd.DataFrame({"object": per.index.astype(str), "successes": k, "attempts": n})
        )
        rows.append(
            {
                "planner": p,
                "objects": len(per),
                "successes": rate.successes,
                "attempts": rate.trials,
                "gsr_percent": 100 * rate.value,
                "wilson_low_percent": 100 * rate.low,
                "wilson_high_percent": 100 * rate.high,
                "objects_low_percent": 100 * low,
                "objects_high_percent": 100 * high,
                "objects_under_50": spread.under_half,
                "worst": spread.worst_text(),
            }
        )
    return pd.DataFrame(rows)


def render_object_level(data: RunData, table: pd.DataFrame) -> list[str]:
    """Markdown lines of the object-level section (none without enough objects)."""
    if table.empty:
        return []
    conf = f"{100 * data.confidence:g} %"
    out = [
        "## Isolated GSR over objects (object-level uncertainty)",
        "",
        "Poses of one object are not independent draws. The interval over objects resamples "
        "whole objects (cluster bootstrap): it is the one to quote for unseen objects. Beside "
        "it, the per-attempt Wilson interval and the spread of per-object GSRs.",
        "",
    ]
    heads = ["planner (isolated)", "GSR", f"Wilson {conf}", f"over objects {conf}",
             "objects < 50 %", "worst five (successes/attempts)"]  # fmt: skip
    out += ["| " + " | ".join(heads) + " |", "|" + "|".join(" --- " for _ in heads) + "|"]
    for _, r in table.iterrows():
        cells = [
            f"{method_label(r['planner'])} ({int(r['objects'])} objects)",
            f"{r['gsr_percent']:.1f}",
            f"[{r['wilson_low_percent']:.1f}, {r['wilson_high_percent']:.1f}]",
            _interval(r["objects_low_percent"], r["objects_high_percent"]),
            f"{int(r['objects_under_50'])}/{int(r['objects'])}",
            str(r["worst"]),
        ]
        out.append("| " + " | ".join(cells) + " |")
    return [*out, ""]


def _interval(low: float, high: float) -> str:
    return "—" if not np.isfinite(low) else f"[{low:.1f}, {high:.1f}]"
