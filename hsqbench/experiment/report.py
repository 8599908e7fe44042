"""Tables and plots of a run, made from its results files alone (``hsqbench report RUN_DIR``).

Definitions (as in the paper, Section V):

- GSR = successful attempts / attempts. Every recorded attempt counts, including "no grasp
  found"; trials that failed with an infrastructure *error* are not attempts and are left out
  (and reported, with a warning).
- CR (packed) = objects removed / objects presented, summed over rounds. Its Wilson interval
  treats objects as independent, which they are not within a round, so it is somewhat too narrow.
- Intervals are Wilson score intervals at the run's confidence level (``run.json``; 95 % if
  absent), pooled over base seeds.

Rows marked "reported, real robot" are the paper's Tables I and II (other robots and setups for
the baselines); rows marked "measured, simulation (this run)" come from this run's files.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.reported import CITATION, PROVENANCE, reported_rows
from hsqbench.experiment.results import (
    ATTEMPT_COLUMNS,
    ROUND_COLUMNS,
    RUN_FILE,
    STATUS_ERROR,
    STATUS_OK,
    load_results,
)
from hsqbench.experiment.stats import Rate, summarize_times
from hsqbench.sim.outcome import Outcome

MEASURED = "measured, simulation (this run)"  # the label of rows from the MuJoCo backend
OUTCOME_COLUMNS = (*[str(o) for o in Outcome], "error")

TABLES_MD = "tables.md"
TABLE1_CSV = "table1_isolated.csv"
TABLE1_OBJECTS_CSV = "table1_per_object.csv"
TABLE2_CSV = "table2_packed.csv"
OUTCOMES_CSV = "outcomes.csv"
TIMES_CSV = "planning_time.csv"
GSR_PLOT = "gsr_per_object.png"
OUTCOMES_PLOT = "outcomes.png"
TIMES_PLOT = "planning_time.png"


@dataclass
class RunData:
    """A run's complete trials as typed frames, and its metadata."""

    attempts: pd.DataFrame
    rounds: pd.DataFrame
    meta: dict[str, Any]
    planners: list[str]
    objects: list[str]
    confidence: float
    notes: list[str] = field(default_factory=list)
    measured: str = MEASURED  # provenance label of this run's rows (names a non-simulation backend)


_NUMERIC = ("success", "attempt_index", "n_attempts", "base_seed", "planning_s", "trial_wall_s")
_ROUND_NUMERIC = ("n_objects", "n_cleared", "n_attempts", "n_success", "base_seed")


def load_run(run_dir: str | Path) -> RunData:
    """Read ``attempts.csv``, ``rounds.csv`` and (if present) ``run.json`` of a run folder.

    Raises:
        FileNotFoundError: ``run_dir`` has no ``attempts.csv``.
    """
    run_dir = Path(run_dir)
    if not (run_dir / "attempts.csv").exists():
        raise FileNotFoundError(
            f"{run_dir}: no attempts.csv; give the folder of a run (results/<run>)"
        )
    results = load_results(run_dir)
    notes = []
    if results.partial_tail:
        notes.append("a partial last line (run killed mid-write) was ignored")
    if results.duplicate_keys:
        notes.append(f"{len(results.duplicate_keys)} trial(s) recorded twice were counted once")
    if results.incomplete_keys:
        notes.append(f"{len(results.incomplete_keys)} incomplete trial(s) were left out")
    meta: dict[str, Any] = {}
    if (run_dir / RUN_FILE).exists():
        meta = json.loads((run_dir / RUN_FILE).read_text())
    attempts = pd.DataFrame(results.attempts, columns=list(ATTEMPT_COLUMNS), dtype=str)
    rounds = pd.DataFrame(results.rounds, columns=list(ROUND_COLUMNS), dtype=str)
    for col in _NUMERIC:
        if col in attempts:
            attempts[col] = pd.to_numeric(attempts[col], errors="coerce")
    for col in _ROUND_NUMERIC:
        if col in rounds:
            rounds[col] = pd.to_numeric(rounds[col], errors="coerce")
    config = meta.get("config", {})
    seen_planners = list(dict.fromkeys(attempts["planner"])) if len(attempts) else []
    planners = [p for p in config.get("planners", []) if p in seen_planners]
    planners += [p for p in seen_planners if p not in planners]
    iso = attempts[attempts["experiment"] == "isolated"] if len(attempts) else attempts
    seen_objects = list(dict.fromkeys(iso["objects"])) if len(iso) else []
    objects = [o for o in config.get("isolated", {}).get("objects", []) if o in seen_objects]
    objects += [o for o in seen_objects if o not in objects]
    hashes = set(attempts["config_hash"]) if len(attempts) else set()
    if len(hashes) > 1:
        notes.append(f"rows carry {len(hashes)} config hashes {sorted(hashes)}: results mixed")
    broken = _stop_rule_violations(attempts, rounds)
    if broken:
        notes.append(
            f"{broken} packed round(s) ended with objects left and without two consecutive "
            "failures: check the trial runner's stop rule"
        )
    confidence = float(config.get("confidence", 0.95))
    backend = meta.get("backend", {}).get("backend")
    if backend == "sim":
        measured = MEASURED
    elif backend is None:
        measured = "measured (this run; backend unknown, run.json missing)"
    else:
        measured = f"measured, {backend} backend (this run)"
    return RunData(attempts, rounds, meta, planners, objects, confidence, notes, measured)


def _stop_rule_violations(attempts: pd.DataFrame, rounds: pd.DataFrame) -> int:
    """Rounds that stopped early: objects left, yet the last two attempts were not failures."""
    count = 0
    ok_rounds = rounds[rounds["status"] == STATUS_OK]
    packed = attempts[(attempts["experiment"] == "packed") & (attempts["status"] == STATUS_OK)]
    by_key = {k: g.sort_values("attempt_index") for k, g in packed.groupby("trial_key")}
    for _, r in ok_rounds.iterrows():
        if r["n_cleared"] >= r["n_objects"]:
            continue
        tail = by_key.get(r["trial_key"])
        if tail is None or len(tail) < 2 or tail["success"].iloc[-2:].sum() > 0:
            count += 1
    return count


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


def _gsr(df: pd.DataFrame, confidence: float) -> Rate | None:
    n = len(df)
    return Rate.of(int(df["success"].sum()), n, confidence) if n else None


def table1(data: RunData) -> pd.DataFrame:
    """Isolated GSR per planner: reported rows, then measured rows with Wilson intervals."""
    rows: list[dict[str, Any]] = []
    for r in reported_rows("isolated"):
        rows.append({"method": r.method, "source": PROVENANCE, "gsr_percent": r.gsr_percent})
    for p in data.planners:
        rate = _gsr(_ok(data.attempts, "isolated", p), data.confidence)
        errors = _errors(data.attempts, "isolated", p)
        if rate is None and not errors:
            continue
        cells = _rate_cells(rate)
        rows.append(
            {
                "method": p,
                "source": data.measured,
                "gsr_percent": 100 * cells["rate"],
                "ci_low_percent": 100 * cells["low"],
                "ci_high_percent": 100 * cells["high"],
                "successes": cells["successes"],
                "attempts": cells["trials"],
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
            rate = _gsr(df[df["objects"] == obj], data.confidence) if len(df) else None
            if rate is None:
                continue
            cells = _rate_cells(rate)
            rows.append(
                {
                    "object": obj,
                    "planner": p,
                    "successes": cells["successes"],
                    "attempts": cells["trials"],
                    "gsr_percent": 100 * cells["rate"],
                    "ci_low_percent": 100 * cells["low"],
                    "ci_high_percent": 100 * cells["high"],
                }
            )
    return pd.DataFrame(rows)


def table2(data: RunData) -> pd.DataFrame:
    """Packed GSR and CR per planner: reported rows, then measured rows with intervals."""
    rows: list[dict[str, Any]] = []
    for r in reported_rows("packed"):
        rows.append(
            {
                "method": r.method,
                "source": PROVENANCE,
                "gsr_percent": r.gsr_percent,
                "cr_percent": r.cr_percent,
            }
        )
    for p in data.planners:
        gsr = _gsr(_ok(data.attempts, "packed", p), data.confidence)
        rounds = data.rounds
        if not rounds.empty:
            rounds = rounds[(rounds["planner"] == p) & (rounds["status"] == STATUS_OK)]
        presented = int(rounds["n_objects"].sum()) if len(rounds) else 0
        cleared = int(rounds["n_cleared"].sum()) if len(rounds) else 0
        cr = Rate.of(cleared, presented, data.confidence) if presented else None
        errors = _errors(data.attempts, "packed", p)
        if gsr is None and cr is None and not errors:
            continue
        g, c = _rate_cells(gsr), _rate_cells(cr)
        rows.append(
            {
                "method": p,
                "source": data.measured,
                "gsr_percent": 100 * g["rate"],
                "gsr_ci_low_percent": 100 * g["low"],
                "gsr_ci_high_percent": 100 * g["high"],
                "successes": g["successes"],
                "attempts": g["trials"],
                "cr_percent": 100 * c["rate"],
                "cr_ci_low_percent": 100 * c["low"],
                "cr_ci_high_percent": 100 * c["high"],
                "objects_cleared": c["successes"],
                "objects_presented": c["trials"],
                "rounds": len(rounds),
                "errors": errors,
            }
        )
    return pd.DataFrame(rows)


def outcome_table(data: RunData) -> pd.DataFrame:
    """Counts of each attempt outcome (and of error trials) per experiment and planner."""
    rows = []
    df = data.attempts
    for exp in ("isolated", "packed"):
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
    for exp in ("isolated", "packed"):
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


# -- markdown ---------------------------------------------------------------------------------


def _md(headers: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join(" --- " for _ in headers) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def _pct(value: float) -> str:
    return "" if value is None or not np.isfinite(value) else f"{value:.1f}"


def _interval(row: pd.Series, prefix: str = "") -> str:
    low, high = row.get(f"{prefix}ci_low_percent"), row.get(f"{prefix}ci_high_percent")
    if low is None or not np.isfinite(low):
        return "—"
    return f"[{low:.1f}, {high:.1f}]"


def render_markdown(
    data: RunData,
    t1: pd.DataFrame,
    t1o: pd.DataFrame,
    t2: pd.DataFrame,
    outcomes: pd.DataFrame,
    times: pd.DataFrame,
) -> str:
    """The human-readable report: both tables beside the paper's rows, outcomes, timings."""
    conf = f"{100 * data.confidence:g} %"
    meta = data.meta
    versions = sorted(set(data.attempts["code_version"])) if len(data.attempts) else []
    out = [f"# Benchmark results: {meta.get('run', '(run)')}", ""]
    out.append(
        f"Config `{meta.get('config_name', '?')}` (hash `{meta.get('config_hash', '?')}`), "
        f"code {', '.join(f'`{v}`' for v in versions) or '?'}, base seeds "
        f"{meta.get('config', {}).get('seeds', '?')}. Intervals: Wilson, {conf}."
    )
    out.append("")
    n_err = int((data.attempts["status"] == STATUS_ERROR).sum()) if len(data.attempts) else 0
    if n_err:
        out += [
            f"**Warning: {n_err} trial(s) failed with an infrastructure error** (column `errors`); "
            "they are not attempts and are left out of GSR and CR. Resume the run with "
            "`--retry-errors` once the cause is fixed.",
            "",
        ]
    out += [f"Note: {n}." for n in data.notes] + ([""] if data.notes else [])

    out += ["## Table I: isolated objects, GSR (%)", ""]
    rows = []
    for _, r in t1.iterrows():
        measured = r["source"] == data.measured
        rows.append(
            [
                str(r["method"]),
                _pct(r["gsr_percent"]),
                _interval(r) if measured else "—",
                f"{int(r['successes'])}/{int(r['attempts'])}" if measured else "—",
                str(int(r["errors"])) if measured else "—",
                str(r["source"]),
            ]
        )
    out += [_md(["method", "GSR", f"{conf} CI", "k/n", "errors", "source"], rows), ""]

    if not t1o.empty:
        out += ["### Isolated GSR per object (successes/attempts, %)", ""]
        planners = [p for p in data.planners if p in set(t1o["planner"])]
        rows = []
        for obj in data.objects:
            sub = t1o[t1o["object"] == obj].set_index("planner")
            cells = [obj]
            for p in planners:
                if p in sub.index:
                    r = sub.loc[p]
                    cells.append(
                        f"{int(r['successes'])}/{int(r['attempts'])} ({r['gsr_percent']:.0f})"
                    )
                else:
                    cells.append("—")
            rows.append(cells)
        out += [_md(["object", *planners], rows), ""]

    out += ["## Table II: packed scenes, GSR and CR (%)", ""]
    rows = []
    for _, r in t2.iterrows():
        measured = r["source"] == data.measured
        rows.append(
            [
                str(r["method"]),
                _pct(r["gsr_percent"]),
                _interval(r, "gsr_") if measured else "—",
                _pct(r["cr_percent"]),
                _interval(r, "cr_") if measured else "—",
                f"{int(r['rounds'])}" if measured else "—",
                str(int(r["errors"])) if measured else "—",
                str(r["source"]),
            ]
        )
    headers = ["method", "GSR", f"GSR {conf} CI", "CR", f"CR {conf} CI", "rounds", "errors"]
    out += [_md([*headers, "source"], rows), ""]

    if not outcomes.empty:
        out += ["## Outcomes per planner (attempt counts; `error` = trials that could not run)", ""]
        cols = [c for c in OUTCOME_COLUMNS if outcomes[c].sum() > 0 or c == "success"]
        rows = [
            [r["experiment"], r["planner"], *[str(int(r[c])) for c in cols]]
            for _, r in outcomes.iterrows()
        ]
        out += [_md(["experiment", "planner", *cols], rows), ""]

    if not times.empty:
        out += ["## Planning time per attempt (s)", ""]
        rows = [
            [
                r["experiment"],
                r["planner"],
                str(int(r["n"])),
                f"{r['median_s']:.3f}",
                f"{r['p90_s']:.3f}",
                f"{r['max_s']:.3f}",
            ]
            for _, r in times.iterrows()
        ]
        out += [_md(["experiment", "planner", "n", "median", "p90", "max"], rows), ""]

    out += [
        "## Notes",
        "",
        "- GSR = successful attempts / attempts (an attempt where no grasp was found counts as "
        "a failed attempt); CR = objects removed / objects presented, summed over rounds.",
        "- The CR interval treats the objects of a round as independent; it is optimistic.",
        f'- "{PROVENANCE}": {CITATION}; the baselines\' numbers come from other robots and '
        "setups, quoted by the paper. They are context, not a like-for-like comparison.",
        f'- "{data.measured}": this run'
        + (", MuJoCo simulation." if data.measured == MEASURED else ", NOT a simulation."),
        "",
    ]
    return "\n".join(out)


# -- plots ------------------------------------------------------------------------------------


def _figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure  # Agg canvas, no pyplot global state

    return Figure(figsize=(width, height), dpi=110, layout="constrained")


def plot_gsr_per_object(data: RunData, t1o: pd.DataFrame, path: Path) -> None:
    fig = _figure(max(6.0, 0.7 * len(data.objects) + 2), 4.2)
    ax = fig.add_subplot()
    planners = [p for p in data.planners if p in set(t1o["planner"])]
    width = 0.8 / max(1, len(planners))
    x = np.arange(len(data.objects))
    for i, p in enumerate(planners):
        sub = t1o[t1o["planner"] == p].set_index("object").reindex(data.objects)
        y = sub["gsr_percent"].to_numpy(dtype=float)
        err = np.vstack(
            [
                y - sub["ci_low_percent"].to_numpy(dtype=float),
                sub["ci_high_percent"].to_numpy(dtype=float) - y,
            ]
        )
        ax.bar(x + (i - (len(planners) - 1) / 2) * width, y, width, yerr=err, capsize=2, label=p)
    ax.set_xticks(x, data.objects, rotation=45, ha="right")
    ax.set_ylabel("GSR (%)")
    ax.set_ylim(0, 118)  # headroom for the legend above the 100 % bars
    ax.set_title(f"Isolated GSR per object ({100 * data.confidence:g} % Wilson intervals)")
    ax.legend(fontsize="small", ncols=max(1, len(planners)), loc="upper left")
    fig.savefig(path)


def plot_outcomes(outcomes: pd.DataFrame, path: Path) -> None:
    fig = _figure(max(5.0, 1.0 * len(outcomes) + 3), 4.2)
    ax = fig.add_subplot()
    labels = [f"{r['planner']}\n{r['experiment']}" for _, r in outcomes.iterrows()]
    bottom = np.zeros(len(outcomes))
    for col in OUTCOME_COLUMNS:
        values = outcomes[col].to_numpy(dtype=float)
        if values.sum() == 0:
            continue
        ax.bar(labels, values, bottom=bottom, label=col)
        bottom += values
    ax.set_ylabel("attempts (error: trials)")
    ax.set_title("Outcome breakdown")
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.savefig(path)


def plot_planning_time(data: RunData, path: Path) -> None:
    ok = data.attempts[data.attempts["status"] == STATUS_OK]
    planners, series = [], []
    for p in data.planners:
        t = ok.loc[ok["planner"] == p, "planning_s"].to_numpy(dtype=float)
        t = t[np.isfinite(t)]
        if t.size:
            planners.append(p)
            series.append(t)
    fig = _figure(max(4.0, 1.2 * len(planners) + 2), 4.0)
    ax = fig.add_subplot()
    ax.boxplot(series, showfliers=True)
    ax.set_xticks(np.arange(1, len(planners) + 1), planners)
    ax.set_ylabel("planning time per attempt (s)")
    ax.set_title("Planning time (both experiments)")
    fig.savefig(path)


def write_report(run_dir: str | Path) -> list[Path]:
    """Write ``tables.md``, the table CSVs and the PNG plots into ``run_dir``; returns the paths.

    Warns (``UserWarning``) when trials failed with infrastructure errors.
    """
    run_dir = Path(run_dir)
    data = load_run(run_dir)
    t1, t1o, t2 = table1(data), table1_per_object(data), table2(data)
    outcomes, times = outcome_table(data), time_table(data)
    written = []
    for name, df in (
        (TABLE1_CSV, t1),
        (TABLE1_OBJECTS_CSV, t1o),
        (TABLE2_CSV, t2),
        (OUTCOMES_CSV, outcomes),
        (TIMES_CSV, times),
    ):
        df.to_csv(run_dir / name, index=False)
        written.append(run_dir / name)
    md = run_dir / TABLES_MD
    md.write_text(render_markdown(data, t1, t1o, t2, outcomes, times))
    written.append(md)
    if not t1o.empty:
        plot_gsr_per_object(data, t1o, run_dir / GSR_PLOT)
        written.append(run_dir / GSR_PLOT)
    if not outcomes.empty:
        plot_outcomes(outcomes, run_dir / OUTCOMES_PLOT)
        written.append(run_dir / OUTCOMES_PLOT)
    if not times.empty:
        plot_planning_time(data, run_dir / TIMES_PLOT)
        written.append(run_dir / TIMES_PLOT)
    n_err = int((data.attempts["status"] == STATUS_ERROR).sum()) if len(data.attempts) else 0
    if n_err:
        warnings.warn(
            f"{n_err} trial(s) in {run_dir} failed with an infrastructure error and are left out "
            "of GSR and CR (see the errors column and attempts.csv detail)",
            stacklevel=2,
        )
    return written
