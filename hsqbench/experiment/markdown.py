"""The human-readable report of a run (``tables.md``): both tables beside the paper's rows,
outcomes and timings (definitions in :mod:`hsqbench.experiment.report`)."""

from __future__ import annotations

import numpy as np
import pandas as pd

from hsqbench.experiment.graspable import PRIVILEGED_NOTE, coverage_from_rows, has_graspability
from hsqbench.experiment.reported import CITATION, PROVENANCE, reported_rows
from hsqbench.experiment.results import STATUS_ERROR
from hsqbench.experiment.run_data import MEASURED, RunData
from hsqbench.sim.outcome import Outcome

OUTCOME_COLUMNS = (*[str(o) for o in Outcome], "error")
#: The tables' two error columns: the planner's own (``planner_error`` attempts, failures in GSR
#: and CR) and the harness's (trials that could not run, left out of both).
ERROR_HEADS = ("planner errors", "infrastructure errors")


def md_table(headers: list[str], rows: list[list[str]]) -> str:
    """A Markdown table (every report, the README's blocks and sweep.md write theirs with it)."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join(" --- " for _ in headers) + "|"]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def signed_pp(v: float) -> str:
    """``+1.2`` / ``−1.2``: a difference in percentage points, with a typographic minus."""
    return f"{v:+.1f}".replace("-", "\u2212")


def p_text(p: float) -> str:
    """A p-value as the tables print it: ``3e-05`` below 0.001, else ``0.012``."""
    return f"{p:.0e}" if p < 1e-3 else f"{p:.3f}"


def _pct(value: float) -> str:
    return "" if value is None or not np.isfinite(value) else f"{value:.1f}"


def _kn(row: pd.Series, k: str, n: str) -> str:
    """``k/n``, or a dash where there is nothing to count (an older run without the column)."""
    total = row.get(n, np.nan)
    return f"{int(row[k])}/{int(total)}" if np.isfinite(total) and total > 0 else "—"


def _error_cells(row: pd.Series, measured: bool) -> list[str]:
    """The planner's own errors (failed attempts, in the rates) and the infrastructure errors
    (trials that could not run, left out), as :data:`ERROR_HEADS`."""
    if not measured:
        return ["—", "—"]
    return [str(int(row["planner_errors"])), str(int(row["errors"]))]


def _interval(row: pd.Series, prefix: str = "") -> str:
    low, high = row.get(f"{prefix}ci_low_percent"), row.get(f"{prefix}ci_high_percent")
    if low is None or not np.isfinite(low):
        return "—"
    return f"[{low:.1f}, {high:.1f}]"


def _seeds(meta: dict) -> str:
    """The base seeds that ran; with ``--until-halfwidth``, why there are that many."""
    until = meta.get("until_halfwidth")
    if not until:
        return str(meta.get("config", {}).get("seeds", "?"))
    target = f"±{100 * until['target_halfwidth']:g} points"
    why = "reached" if until["reached"] else f"not reached within the cap of {until['max_seeds']}"
    return f"{until['seeds_run']} (added until every GSR interval was within {target}: {why})"


def _header(data: RunData, conf: str) -> list[str]:
    """Title, config and code version, error warning and the run's notes."""
    meta = data.meta
    versions = sorted(set(data.attempts["code_version"])) if len(data.attempts) else []
    out = [f"# Benchmark results: {meta.get('run', '(run)')}", ""]
    out.append(
        f"Config `{meta.get('config_name', '?')}` (hash `{meta.get('config_hash', '?')}`), "
        f"code {', '.join(f'`{v}`' for v in versions) or '?'}, base seeds "
        f"{_seeds(meta)}. Intervals ({conf}): Wilson for isolated rates; over rounds (cluster "
        "bootstrap) for packed and pile GSR and CR."
    )
    out.append("")
    n_err = int((data.attempts["status"] == STATUS_ERROR).sum()) if len(data.attempts) else 0
    if n_err:
        out += [
            f"**Warning: {n_err} trial(s) failed with an infrastructure error** (column "
            "`infrastructure errors`); they are not attempts and are left out of GSR and CR. "
            "Resume the run with `--retry-errors` once the cause is fixed.",
            "",
        ]
    out += [f"Note: {n}." for n in data.notes] + ([""] if data.notes else [])
    return out


def _table1(data: RunData, t1: pd.DataFrame, conf: str, graspability: bool) -> list[str]:
    """Table I: GSR on isolated objects per method."""
    out = ["## Table I: isolated objects, GSR (%)", ""]
    if graspability:
        out += [
            "Over all presentations, and over the graspable ones (the oracle found a feasible "
            "grasp on the true meshes at that pose, the same pose for every planner). "
            '"Ungraspable won": successes on presentations the oracle calls ungraspable.',
            "",
        ]
    rows = []
    for _, r in t1.iterrows():
        measured = r["source"] != PROVENANCE
        extra = []
        if graspability:
            extra = [
                _pct(r["graspable_gsr_percent"]) if measured else "—",
                _interval(r, "graspable_") if measured else "—",
                _kn(r, "graspable_successes", "graspable_attempts") if measured else "—",
                _kn(r, "ungraspable_successes", "ungraspable_attempts") if measured else "—",
            ]
        rows.append(
            [
                str(r["method"]),
                _pct(r["gsr_percent"]),
                _interval(r) if measured else "—",
                f"{int(r['successes'])}/{int(r['attempts'])}" if measured else "—",
                *extra,
                *_error_cells(r, measured),
                str(r["source"]),
            ]
        )
    heads = ["method", "GSR", f"{conf} CI", "k/n"]
    if graspability:
        heads += ["GSR graspable", f"{conf} CI", "k/n graspable", "ungraspable won"]
    out += [md_table([*heads, *ERROR_HEADS, "source"], rows), ""]
    out += _coverage(data, "isolated") if graspability else []
    return out


def _coverage(data: RunData, experiment: str) -> list[str]:
    """The line that says whether the oracle is a ceiling for ``experiment``'s presentations."""
    cov = coverage_from_rows(data.attempts, data.rounds)
    if cov is None or experiment not in cov.parts:
        return []
    return [cov.line(experiment), ""]


def _table1_per_object(data: RunData, t1o: pd.DataFrame, graspability: bool) -> list[str]:
    """Isolated GSR per object and planner (nothing when there is no per-object table)."""
    if t1o.empty:
        return []
    out = ["### Isolated GSR per object (successes/attempts, %)", ""]
    planners = [p for p in data.planners if p in set(t1o["planner"])]
    rows = []
    for obj in data.objects:
        sub = t1o[t1o["object"] == obj].set_index("planner")
        cells = [obj]
        if sub.empty:  # every trial of this object failed with an error
            continue
        if graspability:  # the same poses for every planner: the first checked one's count
            checked = sub[sub["checked"] > 0]
            first = checked.iloc[0] if len(checked) else None
            cells.append(
                "—"
                if first is None
                else f"{int(first['graspable_attempts'])}/{int(first['checked'])}"
            )
        for p in planners:
            if p in sub.index:
                r = sub.loc[p]
                cells.append(f"{int(r['successes'])}/{int(r['attempts'])} ({r['gsr_percent']:.0f})")
            else:
                cells.append("—")
        rows.append(cells)
    heads = ["object", *(["graspable"] if graspability else []), *planners]
    out += [md_table(heads, rows), ""]
    return out


def _table2(data: RunData, t2: pd.DataFrame, conf: str, graspability: bool) -> list[str]:
    """Table II: GSR and CR in packed scenes per method."""
    out = ["## Table II: packed scenes, GSR and CR (%)", ""]
    rows = []
    for _, r in t2.iterrows():
        measured = r["source"] != PROVENANCE
        extra = []
        if graspability:
            extra = [
                _pct(r["graspable_cr_percent"]) if measured else "—",
                _interval(r, "graspable_cr_") if measured else "—",
                _kn(r, "ungraspable_successes", "ungraspable_presented") if measured else "—",
            ]
        rows.append(
            [
                str(r["method"]),
                _pct(r["gsr_percent"]),
                _interval(r, "gsr_") if measured else "—",
                _pct(r["cr_percent"]),
                _interval(r, "cr_") if measured else "—",
                *extra,
                f"{int(r['rounds'])}" if measured else "—",
                *_error_cells(r, measured),
                str(r["source"]),
            ]
        )
    headers = ["method", "GSR", f"GSR {conf} CI", "CR", f"CR {conf} CI"]
    if graspability:
        headers += ["CR graspable", f"{conf} CI", "ungraspable won"]
    headers += ["rounds", *ERROR_HEADS]
    out += [md_table([*headers, "source"], rows), ""]
    out += [
        "GSR and CR intervals over rounds (cluster bootstrap): the objects and grasps of one "
        "round share a scene and a sequence, so rounds, not objects, are independent"
        + ("; the graspable columns' intervals are Wilson." if graspability else "."),
        "",
    ]
    if graspability:
        out += [
            "CR graspable: over the objects the oracle can grasp in each round's initial scene "
            '(the same scene for every planner); "ungraspable won": objects grasped of those '
            "it cannot.",
            "",
        ]
        out += _coverage(data, "packed")
    return out


def _outcomes(outcomes: pd.DataFrame) -> list[str]:
    """Attempt counts per outcome and planner."""
    if outcomes.empty:
        return []
    out = [
        "## Outcomes per planner (attempt counts; `planner_error` = the planner raised or "
        "returned an invalid grasp, a failed attempt; `error` = trials that could not run, not "
        "attempts)",
        "",
    ]
    cols = [c for c in OUTCOME_COLUMNS if outcomes[c].sum() > 0 or c == "success"]
    rows = [
        [r["experiment"], r["planner"], *[str(int(r[c])) for c in cols]]
        for _, r in outcomes.iterrows()
    ]
    out += [md_table(["experiment", "planner", *cols], rows), ""]
    return out


def _times(times: pd.DataFrame) -> list[str]:
    """Planning time per attempt: median, p90 and max per planner."""
    if times.empty:
        return []
    out = ["## Planning time per attempt (s)", ""]
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
    out += [md_table(["experiment", "planner", "n", "median", "p90", "max"], rows), ""]
    return out


def _notes(data: RunData, graspability: bool) -> list[str]:
    """Definitions of GSR, CR and graspable, and where each row comes from."""
    out = [
        "## Notes",
        "",
        "- GSR = successful attempts / attempts (an attempt where no grasp was found, or where "
        "the planner raised or returned an invalid grasp, counts as a failed attempt); CR = "
        "objects removed / objects presented, summed over rounds. Trials that could not run "
        "(infrastructure errors) are left out of both.",
        "- The CR interval treats the objects of a round as independent; it is optimistic.",
        *(
            [
                "- Graspable: the oracle (privileged) found a feasible grasp on the true meshes "
                "of a scene every planner shares: an isolated presentation, or a round's "
                "initial scene (CR graspable counts the objects graspable there). Packed GSR is "
                "not conditioned on it: later attempts' scenes are each planner's own.",
                f"- Rows marked (privileged): {PRIVILEGED_NOTE}.",
            ]
            if graspability
            else []
        ),
        (
            f'- "{PROVENANCE}": {CITATION}; the baselines\' numbers come from other robots and '
            "setups, quoted by the paper. They are context, not a like-for-like comparison."
            if any(reported_rows(e, data.meta) for e in ("isolated", "packed"))
            else "- The paper's reported rows are left out: they describe its 15 objects, and "
            "this run's objects are others."
        ),
        f'- "{data.measured}": this run'
        + (", MuJoCo simulation." if data.measured == MEASURED else ", NOT a simulation."),
        *(
            f'- "{label}": the rows of {", ".join(p for p, lab in data.joined.items() if lab == label)}, '
            "from that run (notes above)."
            for label in dict.fromkeys(data.joined.values())
        ),
        "",
    ]
    return out


def render_markdown(
    data: RunData,
    t1: pd.DataFrame,
    t1o: pd.DataFrame,
    t2: pd.DataFrame,
    outcomes: pd.DataFrame,
    times: pd.DataFrame,
    after_table2: list[str] | tuple[str, ...] = (),
) -> str:
    """The human-readable report: both tables beside the paper's rows, outcomes, timings;
    ``after_table2``: lines of further tables (Table IV, :mod:`hsqbench.experiment.pile_table`)."""
    conf = f"{100 * data.confidence:g} %"
    graspability = has_graspability(data.attempts)
    out = _header(data, conf)
    out += _table1(data, t1, conf, graspability)
    out += _table1_per_object(data, t1o, graspability)
    out += _table2(data, t2, conf, graspability)
    out += list(after_table2)
    out += _outcomes(outcomes)
    out += _times(times)
    out += _notes(data, graspability)
    return "\n".join(out)
