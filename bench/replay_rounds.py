"""Replay recorded packed (or pile) rounds with today's code: does a change turn their attempts?

    python bench/replay_rounds.py RUN [RUN ...] [--planner hsq] [--failed-graspable]
        [--rounds 0/2 1/13 ...] [--set execution.turn_down_fractions=[] ...] [--out replay.csv]

Selects rounds of the runs' ``rounds.csv`` (all of ``--planner``'s, those listed as
``base_seed/trial_index`` in ``--rounds``, or with ``--failed-graspable`` those where an attempt
on a graspable presentation failed), replays each from its objects, seed and planner with the
run's trial config (``run.json``), and prints the recorded and the new outcome of every attempt,
and the graspable successes and attempts of both. A replay of unchanged code gives the recorded
outcomes (same seed, same config). ``--set`` replays under changed trial-config values.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))

from replay_attempts import parse_overrides

from hsqbench.sim.trial import load_trial_config, run_packed_round


def _read(run: Path, name: str) -> pd.DataFrame:
    csv = run / name
    return pd.read_csv(csv if csv.exists() else run / f"{name}.gz")


def select_rounds(run: Path, args: argparse.Namespace) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The chosen rounds of ``run`` and the recorded attempts of those rounds."""
    rounds = _read(run, "rounds.csv")
    attempts = _read(run, "attempts.csv")
    attempts = attempts[attempts.experiment == args.experiment]
    rounds = rounds[rounds.trial_key.str.startswith(f"{args.experiment}/")]
    if args.planner:
        rounds = rounds[rounds.planner == args.planner]
        attempts = attempts[attempts.planner == args.planner]
    key = rounds.base_seed.astype(str) + "/" + rounds.trial_index.astype(str)
    if args.rounds:
        rounds = rounds[key.isin(args.rounds)]
    if args.failed_graspable:
        bad = attempts[(attempts.graspable == 1) & (attempts.success == 0)]
        bad_keys = set(zip(bad.planner, bad.base_seed, bad.trial_index, strict=True))
        mask = [(r.planner, r.base_seed, r.trial_index) in bad_keys for r in rounds.itertuples()]
        rounds = rounds[mask]
    return rounds, attempts


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument("--experiment", default="packed", choices=("packed", "pile"))
    p.add_argument("--planner", default="hsq")
    p.add_argument("--rounds", nargs="*", default=[], help="base_seed/trial_index, e.g. 0/2")
    p.add_argument("--failed-graspable", action="store_true")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--out", type=Path, help="CSV of every replayed attempt")
    args = p.parse_args(argv)
    overrides = parse_overrides(args.set)
    rows, totals = [], {"old": [0, 0], "new": [0, 0]}
    for run in args.runs:
        config_name = json.loads((run / "run.json").read_text())["config"]["trial_config"]
        config = load_trial_config(config_name, overrides)
        rounds, attempts = select_rounds(run, args)
        for r in rounds.itertuples():
            old = attempts[
                (attempts.planner == r.planner)
                & (attempts.base_seed == r.base_seed)
                & (attempts.trial_index == r.trial_index)
            ].sort_values("attempt_index")
            result = run_packed_round(
                r.objects.split(";"), int(r.seed), r.planner, config, kind=args.experiment
            )
            new = result.attempts
            print(f"{run.name} {r.planner} {r.base_seed}/{r.trial_index}: {r.objects}", flush=True)
            for i in range(max(len(old), len(new))):
                o = old.iloc[i] if i < len(old) else None
                n = new[i] if i < len(new) else None
                o_txt = "-" if o is None else f"{o.target} {o.outcome} g{o.graspable}"
                n_txt = "-" if n is None else f"{n.target} {n.outcome.value} g{int(n.graspable)}"
                print(f"  {i}: {o_txt:40s} -> {n_txt} | {'' if n is None else n.detail[:150]}")
                if n is not None:
                    rows.append(
                        {
                            "run": run.name,
                            "round": f"{r.base_seed}/{r.trial_index}",
                            "attempt": i,
                            "old": None if o is None else o.outcome,
                            "new": n.outcome.value,
                            "graspable": int(n.graspable),
                            "detail": n.detail,
                        }
                    )
            g_old = old[old.graspable == 1]
            totals["old"][0] += int(g_old.success.sum())
            totals["old"][1] += len(g_old)
            g_new = [a for a in new if a.graspable]
            totals["new"][0] += sum(a.outcome.value == "success" for a in g_new)
            totals["new"][1] += len(g_new)
    for which, (s, n) in totals.items():
        print(f"{which}: graspable successes {s} of {n} attempts")
    if args.out:
        pd.DataFrame(rows).to_csv(args.out, index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
