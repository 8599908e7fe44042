"""Replay recorded isolated attempts with today's code: does a change turn these outcomes?

    python bench/replay_attempts.py RUN [RUN ...] --detail "not in the bin" [--outcome dropped]
        [--planner hsq] [--graspable] [--min-width-m W] [--sample N] [--out replay.csv]
        [--set execution.release_height_m=0.01 ...]

Selects isolated attempts of the runs' ``attempts.csv`` whose detail contains ``--detail`` (and
whose outcome is ``--outcome``), replays each from its object, seed and planner with the run's
trial config (``run.json``), and prints old -> new per attempt and a transition table. A replay
of unchanged code gives the recorded outcome (same seed, same trial). ``--set`` replays under
changed trial-config values (``load_trial_config``'s overrides, YAML-parsed). One process; pair
it with ``--sample`` of the successes to check that a fix breaks none.

This script plans again (a change of the planner or perception shows). To re-execute the grasps
a run recorded, without planning (a change of the execution, or a look at one attempt with
``--rerun``), use ``hsqbench replay RUN``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from hsqbench.sim.trial import load_trial_config, run_isolated_trial


def add_selection_args(p: argparse.ArgumentParser) -> None:
    """The attempt filters of this script (and of replay_rounds.py)."""
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--detail", default="", help="substring of the attempt's detail")
    p.add_argument("--outcome", default="", help="only attempts with this recorded outcome")
    p.add_argument("--planner", default="", help="only attempts of this planner")
    p.add_argument("--graspable", action="store_true", help="only graspable presentations")
    p.add_argument("--min-width-m", type=float, default=0.0, help="only grasps this wide")
    p.add_argument("--sample", type=int, default=0, help="at most this many per run, drawn")
    p.add_argument("--sample-seed", type=int, default=0)


def select_attempts(run: Path, args: argparse.Namespace) -> pd.DataFrame:
    """The isolated attempts of ``run`` that pass the filters of :func:`add_selection_args`."""
    csv = run / "attempts.csv"
    rows = pd.read_csv(csv if csv.exists() else run / "attempts.csv.gz")
    rows = rows[rows.experiment == "isolated"]
    if args.detail:
        rows = rows[rows.detail.str.contains(args.detail, regex=False, na=False)]
    if args.outcome:
        rows = rows[rows.outcome == args.outcome]
    if args.planner:
        rows = rows[rows.planner == args.planner]
    if args.graspable:
        rows = rows[rows.graspable == 1]
    if args.min_width_m:
        rows = rows[rows.width_m >= args.min_width_m]
    if args.sample and len(rows) > args.sample:
        rows = rows.sample(args.sample, random_state=args.sample_seed)
    rows = rows.assign(
        trial_config=json.loads((run / "run.json").read_text())["config"]["trial_config"]
    )
    return rows


def parse_and_select(
    description: str,
    out_help: str,
    argv: list[str] | None,
    extra: Callable[[argparse.ArgumentParser], None] | None = None,
) -> tuple[argparse.Namespace, pd.DataFrame]:
    """The shared command line (filters, ``--out`` and a script's ``extra`` arguments) and the
    attempts it selects over the runs; an empty selection is said on stderr."""
    p = argparse.ArgumentParser(description=description)
    add_selection_args(p)
    p.add_argument("--out", type=Path, help=out_help)
    if extra is not None:
        extra(p)
    args = p.parse_args(argv)
    rows = pd.concat([select_attempts(run, args) for run in args.runs])
    if rows.empty:
        print("no attempt matches", file=sys.stderr)
    return args, rows


def _overrides(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="replay with this trial-config value changed (repeatable)",
    )


def parse_overrides(items: list[str]) -> dict[str, Any]:
    """``["a.b=0.01", ...]`` as ``{"a.b": 0.01}`` (values parsed as YAML)."""
    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise SystemExit(
                f"--set {item!r}: write KEY=VALUE, e.g. execution.release_height_m=0.01"
            )
        out[key.strip()] = yaml.safe_load(value)
    return out


def main(argv: list[str] | None = None) -> int:
    desc = __doc__.splitlines()[0]
    args, rows = parse_and_select(desc, "CSV of key, old, new, new detail", argv, _overrides)
    if rows.empty:
        return 1
    overrides = parse_overrides(args.set)
    out = []
    for r in rows.itertuples():
        obj = r.trial_key.split("/")[3]  # isolated/<planner>/s<seed>/<object>/<index>
        attempt = run_isolated_trial(
            obj, int(r.seed), r.planner, load_trial_config(r.trial_config, overrides)
        )
        new = attempt.attempts[0]
        out.append(
            {
                "trial_key": r.trial_key,
                "old": r.outcome,
                "new": new.outcome.value,
                "detail": new.detail,
            }
        )
        print(f"{r.trial_key}: {r.outcome} -> {new.outcome.value} | {new.detail}", flush=True)
    for (old, new), n in sorted(Counter((o["old"], o["new"]) for o in out).items()):
        print(f"{old} -> {new}: {n}")
    if args.out:
        pd.DataFrame(out).to_csv(args.out, index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
