"""Tables and plots of a run, made from its results files alone (``hsqbench report --run RUN``).

Definitions (as in the paper, Section V):

- GSR = successful attempts / attempts. Every recorded attempt counts, including "no grasp
  found" and the planner's own errors (``planner_error``: it raised, or returned an invalid
  grasp; counted per planner in ``planner_errors``); trials that failed with an
  infrastructure *error* (a harness fault: a scene that could not be built, a worker that died)
  are not attempts and are left out (counted in ``errors``, and reported with a warning).
- CR (packed) = objects removed / objects presented, summed over rounds.
- Intervals of isolated rates are Wilson score intervals at the run's confidence level
  (``run.json``; 95 % if absent), pooled over base seeds; those of packed (and pile) GSR and CR
  are cluster-bootstrap intervals over rounds (:mod:`hsqbench.experiment.cluster`), since the
  objects and grasps of one round are not independent.

Rows marked "reported, real robot" are the paper's Tables I and II (other robots and setups for
the baselines); rows marked "measured, simulation (this run)" come from this run's files, and
"measured, simulation (run NAME)" from run NAME's, joined with ``--join``.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.clutter import rates_over_rounds
from hsqbench.experiment.config import EXPERIMENTS
from hsqbench.experiment.graspable import (
    cr_graspable,
    gsr_graspable,
    method_label,
    ungraspable_successes,
)
from hsqbench.experiment.markdown import OUTCOME_COLUMNS, render_markdown
from hsqbench.experiment.pile_table import TABLE4_CSV, render_table4, table4
from hsqbench.experiment.plots import (  # noqa: F401 (the plot names are the report's API)
    GSR_PLOT,
    HEADLINE_PLOT,
    OUTCOMES_PLOT,
    PAIRED_PLOT,
    TIMES_PLOT,
    write_plots,
)
from hsqbench.experiment.reported import PROVENANCE, reported_rows
from hsqbench.experiment.results import STATUS_ERROR, STATUS_OK
from hsqbench.experiment.run_data import RunData, load_run
from hsqbench.experiment.stats import Rate, summarize_times
from hsqbench.experiment.verdicts import verdict_sections
from hsqbench.sim.outcome import Outcome

TABLES_MD = "tables.md"
TABLE1_CSV = "table1_isolated.csv"
TABLE1_OBJECTS_CSV = "table1_per_object.csv"
TABLE2_CSV = "table2_packed.csv"
OUTCOMES_CSV = "outcomes.csv"
PLANNER_ERROR = str(Outcome.PLANNER_ERROR)
TIMES_CSV = "planning_time.csv"


def _ok(df: pd.DataFrame, experiment: str, planner: str | None = None) -> pd.DataFrame:
    if df.empty:
        return df
    sel = (df["experiment"] == experiment) & (df["status"] == STATUS_OK)
    if planner is not None:
        sel &= df["planner"] == planner
    return df[sel]


def _errors(df: pd.DataFrame, experiment: str, planner: str) -> int:
    if df.empty:
        return 0
    sel = (df["experiment"] == experiment) & (df["status"] == STATUS_ERROR)
    return int((sel & (df["planner"] == planner)).sum())


def _planner_errors(ok: pd.DataFrame) -> int:
    """Attempts of ``ok`` (finished trials' rows) that ended in the planner's own error."""
    return int((ok["outcome"] == PLANNER_ERROR).sum()) if len(ok) else 0


def _rate_cells(rate: Rate | None) -> dict[str, Any]:
    if rate is None:
        return {"successes": 0, "trials": 0, "rate": np.nan, "low": np.nan, "high": np.nan}
    return {
        "successes": rate.successes,
        "trials": rate.trials,
        "rate": rate.value,
        "low": rate.low,
        "high": rate.high,
    }


def _rate_columns(rate: Rate | None, value: str, ci: str, k: str, n: str) -> dict[str, Any]:
    """A rate as table columns: ``value`` (%), ``<ci>ci_low_percent``, ``<ci>ci_high_percent``,
    successes ``k`` and trials ``n``."""
    c = _rate_cells(rate)
    return {
        value: 100 * c["rate"],
        f"{ci}ci_low_percent": 100 * c["low"],
        f"{ci}ci_high_percent": 100 * c["high"],
        k: c["successes"],
        n: c["trials"],
    }


def _gsr(df: pd.DataFrame, confidence: float) -> Rate | None:
    n = len(df)
    return Rate.of(int(df["success"].sum()), n, confidence) if n else None


def table1(data: RunData) -> pd.DataFrame:
    """Isolated GSR per planner: reported rows, then measured rows with Wilson intervals."""
    rows: list[dict[str, Any]] = []
    for r in reported_rows("isolated", data.meta):
        rows.append({"method": r.method, "source": PROVENANCE, "gsr_percent": r.gsr_percent})
    for p in data.planners:
        ok = _ok(data.attempts, "isolated", p)
        rate = _gsr(ok, data.confidence)
        errors = _errors(data.attempts, "isolated", p)
        if rate is None and not errors:
            continue
        graspable = gsr_graspable(ok, data.confidence) if len(ok) else None
        ungraspable = ok[ok["graspable"] == 0] if len(ok) else ok
        rows.append(
            {
                "method": method_label(p),
                "source": data.source(p),
                **_rate_columns(rate, "gsr_percent", "", "successes", "attempts"),
                **_rate_columns(
                    graspable,
                    "graspable_gsr_percent",
                    "graspable_",
                    "graspable_successes",
                    "graspable_attempts",
                ),
                # What the oracle calls ungraspable and this planner grasped: 0 of a ceiling.
                "ungraspable_successes": int(ungraspable["success"].sum()),
                "ungraspable_attempts": len(ungraspable),
                "planner_errors": _planner_errors(ok),
                "errors": errors,
            }
        )
    return pd.DataFrame(rows)


def table1_per_object(data: RunData) -> pd.DataFrame:
    """Isolated GSR per object and planner (long format)."""
    rows = []
    for obj in data.objects:
        for p in data.planners:
            df = _ok(data.attempts, "isolated", p)
            mine = df[df["objects"] == obj] if len(df) else df
            rate = _gsr(mine, data.confidence) if len(mine) else None
            if rate is None:
                continue
            cells = _rate_cells(rate)
            g = _rate_cells(gsr_graspable(mine, data.confidence))
            rows.append(
                {
                    "object": obj,
                    "planner": p,
                    "successes": cells["successes"],
                    "attempts": cells["trials"],
                    "graspable_successes": g["successes"],
                    "graspable_attempts": g["trials"],
                    "checked": int(mine["graspable"].notna().sum()),
                    "gsr_percent": 100 * cells["rate"],
                    "ci_low_percent": 100 * cells["low"],
                    "ci_high_percent": 100 * cells["high"],
                }
            )
    return pd.DataFrame(rows)


def table2(data: RunData) -> pd.DataFrame:
    """Packed GSR and CR per planner: reported rows, then measured rows with intervals."""
    rows: list[dict[str, Any]] = []
    for r in reported_rows("packed", data.meta):
        rows.append(
            {
                "method": r.method,
                "source": PROVENANCE,
                "gsr_percent": r.gsr_percent,
                "cr_percent": r.cr_percent,
            }
        )
    beyond = ungraspable_successes(data.attempts, data.rounds)
    beyond = beyond[beyond["experiment"] == "packed"].set_index("planner")
    for p in data.planners:
        ok = _ok(data.attempts, "packed", p)
        gsr = _gsr(ok, data.confidence)
        rounds = data.rounds
        if not rounds.empty:  # packed rounds only: pile rounds are Table IV's
            packed = rounds["trial_key"].astype(str).str.startswith("packed/")
            rounds = rounds[packed & (rounds["planner"] == p) & (rounds["status"] == STATUS_OK)]
        presented = int(rounds["n_objects"].sum()) if len(rounds) else 0
        cleared = int(rounds["n_cleared"].sum()) if len(rounds) else 0
        cr = Rate.of(cleared, presented, data.confidence) if presented else None
        errors = _errors(data.attempts, "packed", p)
        if gsr is None and cr is None and not errors:
            continue
        # Graspable: the objects of each round's initial scene, shared by every planner; later
        # attempts' scenes are the planner's own, so packed GSR is not conditioned on it.
        cr_g = cr_graspable(rounds, data.confidence) if len(rounds) else None
        rows.append(
            {
                "method": method_label(p),
                "source": data.source(p),
                **_rate_columns(gsr, "gsr_percent", "gsr_", "successes", "attempts"),
                **_rate_columns(cr, "cr_percent", "cr_", "objects_cleared", "objects_presented"),
                **rates_over_rounds(ok, rounds, data.confidence),
                **_rate_columns(
                    cr_g,
                    "graspable_cr_percent",
                    "graspable_cr_",
                    "graspable_objects_cleared",
                    "graspable_objects_presented",
                ),
                # Objects not graspable in the round's initial scene, and how many it grasped.
                "ungraspable_successes": int(beyond["successes"].get(p, 0)),
                "ungraspable_presented": int(beyond["presented"].get(p, 0)),
                "rounds": len(rounds),
                "planner_errors": _planner_errors(ok),
                "errors": errors,
            }
        )
    return pd.DataFrame(rows)


def outcome_table(data: RunData) -> pd.DataFrame:
    """Counts of each attempt outcome (``planner_error`` among them) and of error trials
    (infrastructure errors, not attempts) per experiment and planner."""
    rows = []
    df = data.attempts
    for exp in EXPERIMENTS:
        for p in data.planners:
            sel = df[(df["experiment"] == exp) & (df["planner"] == p)] if len(df) else df
            if sel.empty:
                continue
            ok = sel[sel["status"] == STATUS_OK]
            counts = {o: int((ok["outcome"] == o).sum()) for o in OUTCOME_COLUMNS[:-1]}
            counts["error"] = int((sel["status"] == STATUS_ERROR).sum())
            rows.append({"experiment": exp, "planner": p, **counts, "attempts": len(ok)})
    return pd.DataFrame(rows)


def time_table(data: RunData) -> pd.DataFrame:
    """Planning time per experiment and planner (median, p90, mean, max), seconds."""
    rows = []
    for exp in EXPERIMENTS:
        for p in data.planners:
            ok = _ok(data.attempts, exp, p)
            times = ok["planning_s"].to_numpy(dtype=float) if len(ok) else np.array([])
            if not np.isfinite(times).any():
                continue
            s = summarize_times(times)
            rows.append(
                {
                    "experiment": exp,
                    "planner": p,
                    "n": s.n,
                    "median_s": s.median_s,
                    "p90_s": s.p90_s,
                    "mean_s": s.mean_s,
                    "max_s": s.max_s,
                }
            )
    return pd.DataFrame(rows)


def write_report(
    run_dir: str | Path, with_runs: tuple[str | Path, ...] = (), reference: str | None = None
) -> list[Path]:
    """Write ``tables.md``, the table CSVs and the PNG plots into ``run_dir``; returns the paths.

    ``with_runs``: other runs of the same protocol whose further planners join the tables
    (:mod:`hsqbench.experiment.combine`). ``reference``: the planner the paired section compares
    every other with (default hsq; :mod:`hsqbench.experiment.verdicts`). Warns
    (``UserWarning``) when trials failed with infrastructure errors.

    Raises:
        ValueError: ``reference`` did not run.
    """
    from hsqbench.experiment.combine import combine

    run_dir = Path(run_dir)
    data = load_run(run_dir)
    for other in with_runs:
        combine(data, load_run(other), Path(other))
    t1, t1o, t2 = table1(data), table1_per_object(data), table2(data)
    outcomes, times = outcome_table(data), time_table(data)
    t4 = table4(data)
    judged, judged_lines = verdict_sections(data, reference)
    written = []
    for name, df in (
        (TABLE1_CSV, t1),
        (TABLE1_OBJECTS_CSV, t1o),
        (TABLE2_CSV, t2),
        (OUTCOMES_CSV, outcomes),
        (TIMES_CSV, times),
        *judged.items(),
    ):
        df.to_csv(run_dir / name, index=False)
        written.append(run_dir / name)
    if not t4.empty:
        t4.to_csv(run_dir / TABLE4_CSV, index=False)
        written.append(run_dir / TABLE4_CSV)
    md = run_dir / TABLES_MD
    after = [*render_table4(data, t4), *judged_lines]
    md.write_text(render_markdown(data, t1, t1o, t2, outcomes, times, after))
    written.append(md)
    written += write_plots(data, t1o, outcomes, judged, run_dir)
    n_err = int((data.attempts["status"] == STATUS_ERROR).sum()) if len(data.attempts) else 0
    if n_err:
        warnings.warn(
            f"{n_err} trial(s) in {run_dir} failed with an infrastructure error and are left out "
            "of GSR and CR (see the errors column and attempts.csv detail; a planner's own "
            "errors are failed attempts, column planner_errors)",
            stacklevel=2,
        )
    return written
