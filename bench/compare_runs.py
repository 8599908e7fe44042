"""Compare two runs trial by trial: do the same seeds give the same outcomes?

    python bench/compare_runs.py RUN_A RUN_B [--columns outcome,target,...] [--show N]

Reads each run's ``attempts.csv`` and matches attempts by (``trial_key``, ``attempt_index``).
The columns that a behaviour-preserving change must leave alone (:data:`MATCH`) are compared
exactly; timings, workers, hashes and code versions are not. Prints the counts of identical and
changed attempts, trials only in one run, a transition table of outcomes (old -> new) and every
differing attempt with the columns that differ. Exit status 0 when every matched attempt is
identical and both runs hold the same trials, 1 otherwise.
"""

from __future__ import annotations

import argparse
import csv
import sys
from collections import Counter
from pathlib import Path

from hsqbench.experiment.rows import ATTEMPT_COLUMNS

#: Columns that need not match for the same trial: timings, the worker, hashes, versions.
UNFIXED = {
    "perception_s",
    "planning_s",
    "execution_s",
    "trial_wall_s",
    "worker",
    "config_hash",
    "code_version",
    "finished_at",
}
#: Columns that must match for the same trial (the seeds fix them): every other column of
#: attempts.csv but the key.
MATCH = tuple(c for c in ATTEMPT_COLUMNS if c not in UNFIXED | {"trial_key", "attempt_index"})
KEY = ("trial_key", "attempt_index")


def read_attempts(run: Path) -> dict[tuple[str, str], dict[str, str]]:
    path = run / "attempts.csv" if run.is_dir() else run
    if not path.exists():
        raise SystemExit(f"compare_runs: {path} does not exist (give a run folder or its CSV)")
    with path.open(newline="") as f:
        return {(r["trial_key"], r["attempt_index"]): r for r in csv.DictReader(f)}


def compare(
    a: dict[tuple[str, str], dict[str, str]],
    b: dict[tuple[str, str], dict[str, str]],
    columns: tuple[str, ...],
) -> tuple[list[tuple[tuple[str, str], list[str]]], Counter, list, list]:
    """(differing attempts with their differing columns, outcome transitions, keys only in
    ``a``, keys only in ``b``)."""
    diffs = []
    transitions: Counter = Counter()
    for key in sorted(set(a) & set(b)):
        ra, rb = a[key], b[key]
        transitions[(ra.get("outcome", ""), rb.get("outcome", ""))] += 1
        changed = [c for c in columns if ra.get(c) != rb.get(c)]
        if changed:
            diffs.append((key, changed))
    only_a = sorted(set(a) - set(b))
    only_b = sorted(set(b) - set(a))
    return diffs, transitions, only_a, only_b


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run_a", type=Path)
    parser.add_argument("run_b", type=Path)
    parser.add_argument(
        "--columns", default=",".join(MATCH), help="comma-separated columns that must match"
    )
    parser.add_argument("--show", type=int, default=200, help="differing attempts listed")
    args = parser.parse_args(argv)
    columns = tuple(c for c in args.columns.split(",") if c)
    a, b = read_attempts(args.run_a), read_attempts(args.run_b)
    diffs, transitions, only_a, only_b = compare(a, b, columns)
    matched = sum(transitions.values())
    trials_a = {k[0] for k in a}
    trials_b = {k[0] for k in b}
    changed_trials = {k[0] for k, _ in diffs}
    print(f"A: {args.run_a} ({len(a)} attempts, {len(trials_a)} trials)")
    print(f"B: {args.run_b} ({len(b)} attempts, {len(trials_b)} trials)")
    print(
        f"matched attempts: {matched}; identical: {matched - len(diffs)}; changed: {len(diffs)} "
        f"(in {len(changed_trials)} of {len(trials_a & trials_b)} common trials)"
    )
    print(f"attempts only in A: {len(only_a)}; only in B: {len(only_b)}")
    print("\noutcome transitions (A -> B): count")
    for (oa, ob), n in sorted(transitions.items(), key=lambda kv: (-kv[1], kv[0])):
        mark = "" if oa == ob else "   <- changed"
        print(f"  {oa or '-':>22} -> {ob or '-':<22} {n:5d}{mark}")
    by_column = Counter(c for _, cols in diffs for c in cols)
    if by_column:
        print("\ncolumns that differ (attempts):", dict(by_column.most_common()))
    if diffs:
        print(f"\ndiffering attempts (first {min(args.show, len(diffs))} of {len(diffs)}):")
        for (trial, index), cols in diffs[: args.show]:
            ra, rb = a[(trial, index)], b[(trial, index)]
            print(f"- {trial} attempt {index}:")
            for c in cols:
                print(f"    {c}: {ra.get(c)!r} -> {rb.get(c)!r}")
    for name, keys in (("A", only_a), ("B", only_b)):
        for trial, index in keys[: args.show]:
            print(f"- only in {name}: {trial} attempt {index}")
    return 0 if not diffs and not only_a and not only_b else 1


if __name__ == "__main__":
    sys.exit(main())
