"""``hsqbench compare A B``: two runs of one protocol, trial by trial.

Judges a change to a planner, a config or the simulation in one command: per planner, the
paired difference B - A (isolated GSR over the same poses, packed and pile CR over the same
draws' rounds) with its interval and test, Holm-adjusted over all of them, the outcome
transitions, the objects whose attempts changed, and every attempt whose recorded columns
differ. Runs of different protocols, seeds or draws are refused (exit 2), as is a pair of runs
with nothing in common.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import RUN_HELP, add_planners, as_path

HELP = "compare two runs of one protocol trial by trial: paired differences and changed attempts"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run_a", type=as_path, metavar="A", help=f"the baseline run ({RUN_HELP})")
    parser.add_argument("run_b", type=as_path, metavar="B", help="the run to judge against it")
    add_planners(parser, "only these planners")
    parser.add_argument(
        "--columns",
        nargs="+",
        default=None,
        metavar="COLUMN",
        help="the columns that must match for an attempt to count as unchanged (default: every "
        "column the seeds fix, not timings, workers, hashes or versions)",
    )
    parser.add_argument(
        "--part",
        action="store_true",
        help="B ran part of A's trials (a smaller protocol on the same seeds, e.g. a few objects "
        "to check that this code still gives a committed run): A's other trials are left out",
    )
    parser.add_argument(
        "--limit",
        dest="show",
        type=int,
        default=50,
        metavar="N",
        help="at most this many changed attempts listed (default 50)",
    )
    deprecated(parser, "--show", "--limit", "show", type=int, default=50)
    parser.add_argument(
        "--fail-if-worse",
        action="store_true",
        help="exit 1 when B is significantly worse than A for some planner (Holm-adjusted p "
        "below 1 - the run's confidence): for CI",
    )
    parser.add_argument(
        "--fail-if-changed",
        action="store_true",
        help="exit 1 when any matched attempt differs or a trial is in one run only (a "
        "change meant to preserve behaviour)",
    )


def _describe(name: str, path: Path, data: Any) -> str:
    attempts = data.attempts
    versions = ", ".join(sorted(set(attempts["code_version"]))) if len(attempts) else "?"
    trials = attempts["trial_key"].nunique() if len(attempts) else 0
    return (
        f"{name}: {path} (config {data.meta.get('config_name', '?')}, hash "
        f"{data.meta.get('config_hash', '?')}, code {versions}; {len(attempts)} attempts in "
        f"{trials} trials)"
    )


def _print_differences(differences: Any, confidence: float) -> None:
    conf = f"{100 * confidence:g} %"
    print(
        f"\npaired difference B - A ({conf} CI; isolated: Newcombe and exact McNemar over the "
        "presentations; CR: bootstrap and exact sign-flip over rounds; p Holm over these tests):"
    )
    print(
        f"  {'comparison':<13} {'planner':<22} {'A %':>6} {'B %':>6} {'B - A [CI] (pp)':>24} "
        f"{'s->f':>5} {'f->s':>5} {'pairs':>6} {'over':>14} {'p':>8} {'p Holm':>8}  B against A"
    )
    for _, r in differences.iterrows():
        low, high = r["ci_low_pp"], r["ci_high_pp"]
        # No interval over a single round (or pair): a dash, as the report's tables print it.
        ci = "[—]" if low != low or high != high else f"[{low:+.1f}, {high:+.1f}]"
        diff = f"{r['difference_pp']:+.1f} {ci}"
        print(
            f"  {r['comparison']:<13} {r['planner']:<22} {r['a_percent']:6.1f} "
            f"{r['b_percent']:6.1f} {diff:>24} {int(r['success_to_failure']):5d} "
            f"{int(r['failure_to_success']):5d} {int(r['pairs']):6d} {r['over']:>14} "
            f"{r['p_value']:8.3g} {r['p_holm']:8.3g}  {r['verdict']}"
        )


def _print_changes(merged: Any, objects: Any, diffs: list, show: int) -> None:
    from hsqbench.experiment.run_compare import outcome_transitions

    if not objects.empty:
        print("\nisolated attempts that changed, per planner and object (s->f, f->s of pairs):")
        for _, r in objects.iterrows():
            print(
                f"  {r['planner']:<22} {r['object']:<28} {int(r['lost']):3d} lost "
                f"{int(r['won']):3d} won of {int(r['pairs'])}"
            )
    print("\noutcome transitions (A -> B): attempts")
    transitions = outcome_transitions(merged)
    for (oa, ob), n in sorted(transitions.items(), key=lambda kv: (-kv[1], kv[0])):
        mark = "" if oa == ob else "   <- changed"
        print(f"  {oa:>22} -> {ob:<22} {n:5d}{mark}")
    if not diffs:
        return
    by_column: dict[str, int] = {}
    for _, cols in diffs:
        for c in cols:
            by_column[c] = by_column.get(c, 0) + 1
    print(
        "\ncolumns that differ (attempts):", dict(sorted(by_column.items(), key=lambda kv: -kv[1]))
    )
    print(f"\nchanged attempts (first {min(show, len(diffs))} of {len(diffs)}):")
    rows = merged.set_index(["trial_key", "attempt_index"])
    for (trial, index), cols in diffs[:show]:
        r = rows.loc[(trial, index)]
        changes = "; ".join(
            f"{c}: {_value(r[f'{c}_a'])} -> {_value(r[f'{c}_b'])}" for c in cols[:4]
        )
        more = f" (+{len(cols) - 4} columns)" if len(cols) > 4 else ""
        print(f"  {trial} attempt {int(index)}: {changes}{more}")


def _value(v: Any) -> str:
    """A cell as the CSV holds it: text quoted (an empty one shows), numbers plain."""
    return repr(v) if isinstance(v, str) else f"{v:g}" if isinstance(v, float) else str(v)


def _pair_up(args: argparse.Namespace, a: Any, b: Any) -> None:
    """Keep the chosen planners of both runs and, with ``--part``, only A's trials B ran.

    Raises:
        RunMismatch: the runs do not hold the same trials (or, with ``--part``, B's are not
            A's).
        ValueError: with ``--part``, B holds no trial.
    """
    from hsqbench.experiment.combine import check_part_of, check_same_trials

    if args.planners is not None:
        for data in (a, b):
            data.attempts = data.attempts[data.attempts["planner"].isin(args.planners)]
            data.rounds = data.rounds[data.rounds["planner"].isin(args.planners)]
    whose = f"{args.run_a}'s"
    if args.part:
        check_part_of(a, b, args.run_b, whose)
        ran = set(b.attempts["trial_key"]) | set(b.rounds["trial_key"])
        if not ran:
            raise ValueError(f"--part: {args.run_b} has no trials")
        a.attempts = a.attempts[a.attempts["trial_key"].isin(ran)]
        a.rounds = a.rounds[a.rounds["trial_key"].isin(ran)]
    else:
        check_same_trials(a, b, args.run_b, whose)


def run(args: argparse.Namespace) -> int:
    from hsqbench.experiment.combine import RunMismatch
    from hsqbench.experiment.report import load_run
    from hsqbench.experiment.run_compare import (
        MATCH,
        changed_attempts,
        matched_attempts,
        object_transitions,
        run_differences,
        worse,
    )

    for path in (args.run_a, args.run_b):
        if not path.is_dir():
            raise FileNotFoundError(f"{path} is not a folder; give two run folders runs/<run>")
    a, b = load_run(args.run_a), load_run(args.run_b)
    # Space-separated as every list of this CLI; "a,b" (the old form) is read alike.
    given = [c for item in args.columns or () for c in item.split(",") if c]
    columns = tuple(given) or MATCH
    unknown = [c for c in columns if c not in MATCH]
    if unknown:
        raise ValueError(f"--columns {','.join(unknown)}: not compared columns; use of {MATCH}")
    _pair_up(args, a, b)
    merged = matched_attempts(a, b)
    diffs = changed_attempts(merged, columns)
    differences = run_differences(a, b, merged)
    only_a = int((merged["_merge"] == "left_only").sum())
    only_b = int((merged["_merge"] == "right_only").sum())
    matched = len(merged) - only_a - only_b
    if matched == 0 or differences.empty:
        raise RunMismatch(
            f"{args.run_a} and {args.run_b}: no attempt or round pairs up (trial key, planner "
            "and draw); compare runs of the same protocol that share planners"
        )
    print(_describe("A", args.run_a, a))
    print(_describe("B", args.run_b, b))
    print(
        f"matched attempts: {matched}; identical: {matched - len(diffs)}; changed: {len(diffs)} "
        f"(in {len({k[0] for k, _ in diffs})} trials); only in A: {only_a}; only in B: {only_b}"
    )
    _print_differences(differences, a.confidence)
    _print_changes(merged, object_transitions(merged), diffs, args.show)
    status = 0
    if args.fail_if_changed and (diffs or only_a or only_b):
        print("\nFAIL: the runs differ (--fail-if-changed)")
        status = 1
    bad = worse(differences)
    if args.fail_if_worse and not bad.empty:
        names = ", ".join(f"{r['planner']} ({r['comparison']})" for _, r in bad.iterrows())
        print(f"\nFAIL: B is significantly worse than A for {names} (--fail-if-worse)")
        status = 1
    return status
