"""The table of a sweep (``sweep.csv``): a rate with its Wilson interval per protocol,
experiment, parameter, point and planner, read from the points' run folders. ``value`` is the
point's label, ``x`` its position on the plot (empty for categories such as the cameras).

Isolated: GSR (successful attempts / attempts). Packed: GSR over all attempts of the rounds, and
CR (objects cleared / objects presented). Error rows (infrastructure failures) are counted in
``errors`` and left out of the rates, as in the report's tables.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pandas as pd

from hsqbench.experiment.results import STATUS_ERROR, STATUS_OK
from hsqbench.experiment.rows import has_attempts
from hsqbench.experiment.stats import Rate

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


def run_rows(run_dir: Path, experiments: list[str]) -> list[dict[str, Any]]:
    """Per experiment and planner of one run: n, successes, GSR (and CR) with intervals."""
    from hsqbench.experiment.report import load_run

    data = load_run(run_dir)
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


def sweep_table(root: Path, meta: dict[str, Any]) -> pd.DataFrame:
    """Every recorded point whose run has results; points not run yet are left out."""
    rows = []
    for name, param in meta["parameters"].items():
        for i, point in enumerate(param["points"]):
            for protocol, rel in point["runs"].items():
                run_dir = root / rel
                if not has_attempts(run_dir):
                    continue
                for row in run_rows(run_dir, param["experiments"]):
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
                        }
                    )
    return pd.DataFrame(rows, columns=list(COLUMNS))
