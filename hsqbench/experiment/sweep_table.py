"""The table of a sweep (``sweep.csv``): a rate with its Wilson interval per protocol,
experiment, parameter, point and planner, read from the points' run folders. ``value`` is the
point's label, ``x`` its position on the plot (empty for categories such as the cameras).

Isolated: GSR (successful attempts / attempts). Packed: GSR over all attempts of the rounds, and
CR (objects cleared / objects presented). Attempts that ended in the planner's own error are
failed attempts, in the rates and counted in ``planner_errors``; error rows (infrastructure
failures) are counted in ``errors`` and left out of the rates, as in the report's tables.

Every point runs the same presentations, so each point is also compared with its parameter's
default point (the one without overrides) as ``hsqbench compare`` compares two runs
(:mod:`hsqbench.experiment.run_compare`): isolated GSR over paired attempts, packed and pile CR
over paired rounds. ``vs_default_*`` hold the difference in percentage points with its interval,
the p-value, the p Holm-adjusted over that point's tests against its default (one ``compare``)
and the verdict from it; empty at the default itself and where a sweep has no default point.
"""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path
from typing import Any

import pandas as pd

from hsqbench.experiment.results import STATUS_ERROR, STATUS_OK
from hsqbench.experiment.rows import has_attempts
from hsqbench.experiment.run_compare import matched_attempts, run_differences
from hsqbench.experiment.run_data import RunData, load_run
from hsqbench.experiment.stats import Rate
from hsqbench.sim.outcome import Outcome

COLUMNS = (
    "protocol",
    "experiment",
    "parameter",
    "point",
    "value",
    "x",
    "overrides",
    "planner",
    "n",
    "successes",
    "gsr_percent",
    "gsr_ci_low_percent",
    "gsr_ci_high_percent",
    "objects_presented",
    "objects_cleared",
    "cr_percent",
    "cr_ci_low_percent",
    "cr_ci_high_percent",
    # PairedDifference.summary_columns (through run_compare.run_differences), prefixed
    "vs_default_difference_pp",
    "vs_default_ci_low_pp",
    "vs_default_ci_high_pp",
    "vs_default_p_value",
    "vs_default_p_holm",
    "vs_default_verdict",
    "planner_errors",
    "errors",
    "confidence",
    "run",
)


def _rate(k: int, n: int, confidence: float, prefix: str) -> dict[str, float]:
    if n == 0:
        return {f"{prefix}_percent": float("nan"), f"{prefix}_ci_low_percent": float("nan"),
                f"{prefix}_ci_high_percent": float("nan")}  # fmt: skip
    r = Rate.of(k, n, confidence)
    return {
        f"{prefix}_percent": 100 * r.value,
        f"{prefix}_ci_low_percent": 100 * r.low,
        f"{prefix}_ci_high_percent": 100 * r.high,
    }


def run_rows(data: RunData, experiments: list[str]) -> list[dict[str, Any]]:
    """Per experiment and planner of one run: n, successes, GSR (and CR) with intervals."""
    rows = []
    a, r = data.attempts, data.rounds
    for experiment in experiments:
        for planner in data.planners:
            mine = a[(a["experiment"] == experiment) & (a["planner"] == planner)]
            ok = mine[mine["status"] == STATUS_OK]
            errors = int((mine["status"] == STATUS_ERROR).sum())
            if not len(ok) and not errors:
                continue
            n, k = len(ok), int(ok["success"].sum())
            row: dict[str, Any] = {
                "experiment": experiment,
                "planner": planner,
                "n": n,
                "successes": k,
                **_rate(k, n, data.confidence, "gsr"),
                "planner_errors": int((ok["outcome"] == str(Outcome.PLANNER_ERROR)).sum()),
                "errors": errors,
                "confidence": data.confidence,
            }
            if experiment in ("packed", "pile"):  # CR over this experiment's rounds only
                mine_r = (
                    r["trial_key"].astype(str).str.startswith(f"{experiment}/") if len(r) else r
                )
                rounds = (
                    r[mine_r & (r["planner"] == planner) & (r["status"] == STATUS_OK)]
                    if len(r)
                    else r
                )
                presented = int(rounds["n_objects"].sum()) if len(rounds) else 0
                cleared = int(rounds["n_cleared"].sum()) if len(rounds) else 0
                row |= {"objects_presented": presented, "objects_cleared": cleared}
                row |= _rate(cleared, presented, data.confidence, "cr")
            rows.append(row)
    return rows


#: ``run_differences``' comparison -> the experiment of a sweep row.
COMPARED = {"isolated GSR": "isolated", "packed CR": "packed", "pile CR": "pile"}
PAIRED = ("difference_pp", "ci_low_pp", "ci_high_pp", "p_value", "p_holm", "verdict")


def default_point(param: dict[str, Any]) -> dict[str, Any] | None:
    """The point of a recorded parameter that changes nothing (None: the sweep has none)."""
    return next((p for p in param["points"] if not p["overrides"]), None)


def _vs_default(data: RunData, default: RunData) -> dict[tuple[str, str], dict[str, Any]]:
    """(experiment, planner) -> the ``vs_default_*`` columns: ``data`` (B) against ``default``
    (A), paired trial by trial."""
    diffs = run_differences(default, data, matched_attempts(default, data))
    return {
        (COMPARED[r["comparison"]], r["planner"]): {f"vs_default_{c}": r[c] for c in PAIRED}
        for r in diffs.to_dict("records")
    }


def sweep_table(root: Path, meta: dict[str, Any]) -> pd.DataFrame:
    """Every recorded point whose run has results; points not run yet are left out."""

    @cache
    def run(rel: str) -> RunData | None:
        return load_run(root / rel) if has_attempts(root / rel) else None

    rows = []
    for name, param in meta["parameters"].items():
        default = default_point(param)
        for i, point in enumerate(param["points"]):
            for protocol, rel in point["runs"].items():
                data = run(rel)
                if data is None:
                    continue
                ref = run(default["runs"][protocol]) if default and point is not default else None
                paired = _vs_default(data, ref) if ref is not None else {}
                for row in run_rows(data, param["experiments"]):
                    rows.append(
                        {
                            "protocol": protocol,
                            "parameter": name,
                            "point": i,
                            "value": point["label"],
                            "x": point["x"],
                            "overrides": json.dumps(point["overrides"], sort_keys=True),
                            "run": rel,
                            **row,
                            **paired.get((row["experiment"], row["planner"]), {}),
                        }
                    )
    return pd.DataFrame(rows, columns=list(COLUMNS))
