"""``hsqbench replay RUN``: re-execute recorded grasps of a benchmark run, without planning."""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

HELP = "re-execute grasps recorded in a run's attempts.csv (no planning) and compare outcomes"

_EPILOG = """\
Each chosen trial is set up again from its seed and objects with the run's trial config
(run.json), and its attempts execute the grasps that attempts.csv recorded (grasp_pose,
grasp_flipped, width_m) instead of asking the planner. A packed or pile round is replayed from
its first attempt up to --attempt. Each replayed attempt is printed as
`KEY #I: RECORDED -> REPLAYED (detail)`.

Examples:
  hsqbench replay runs/quick --trial isolated/hsq/s0/mug/000
  hsqbench replay runs/quick --outcome dropped --limit 5 --set execution.release_height_m=0.01
  hsqbench replay runs/quick --trial packed/hsq/s0/003 --attempt 2 --rerun round.rrd

The replay is exact when the executed grasp was the first one motion-planned (ranks_tried 1);
otherwise the inverse kinematics draws other restarts and a borderline attempt may differ
(marked `~`). Runs made before attempts.csv recorded grasp poses cannot be replayed this way:
`python bench/replay_attempts.py RUN` plans them again instead.

Exit status: 0 when every replayed attempt ended as recorded, 1 when one did not, 2 on bad
input.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("run", type=Path, metavar="RUN", help="a benchmark run folder")
    parser.add_argument(
        "--trial",
        action="append",
        default=None,
        metavar="KEY",
        help="replay this trial (its trial_key in attempts.csv; repeatable)",
    )
    parser.add_argument(
        "--attempt",
        type=int,
        default=None,
        metavar="N",
        help="replay up to this attempt index of each trial (default: all its attempts)",
    )
    parser.add_argument(
        "--outcome", default=None, metavar="NAME", help="without --trial: trials with this outcome"
    )
    parser.add_argument(
        "--planner", default=None, metavar="NAME", help="without --trial: trials of this planner"
    )
    parser.add_argument(
        "--limit",
        type=int,
        default=10,
        metavar="N",
        help="without --trial: at most this many trials (default 10)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="replay with this trial-config value changed, e.g. execution.release_height_m=0.01",
    )
    parser.add_argument(
        "--rerun", type=Path, default=None, metavar="OUT.rrd", help="record the replay (one trial)"
    )


def _overrides(items: list[str]) -> dict[str, object]:
    import yaml

    from hsqbench.cli import CommandError

    out: dict[str, object] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise CommandError(
                f"--set {item!r}: write KEY=VALUE, e.g. execution.release_height_m=0.01"
            )
        out[key.strip()] = yaml.safe_load(value)
    return out


def _chosen_keys(args: argparse.Namespace, rows: list[dict[str, str]]) -> list[str]:
    from hsqbench.cli import CommandError

    if args.trial:
        return list(args.trial)
    keys = []
    for r in rows:
        if r["status"] != "ok" or r["trial_key"] in keys:
            continue
        if args.outcome and r["outcome"] != args.outcome:
            continue
        if args.planner and r["planner"] != args.planner:
            continue
        keys.append(r["trial_key"])
    if not keys:
        raise CommandError(f"{args.run}: no finished trial matches --outcome / --planner")
    if len(keys) > args.limit:
        print(f"{len(keys)} trials match; replaying the first {args.limit} (--limit)")
    return keys[: args.limit]


def run(args: argparse.Namespace) -> int:
    from hsqbench.cli import CommandError
    from hsqbench.experiment.replay import replay_trial, run_rows, trial_rows
    from hsqbench.viz.episodes import run_trial_config

    if args.limit < 1:
        raise CommandError(f"--limit must be >= 1, got {args.limit}")
    rows = run_rows(args.run)
    config = run_trial_config(args.run, _overrides(args.set))
    keys = _chosen_keys(args, rows)
    if args.rerun is not None and len(keys) != 1:
        raise CommandError(f"--rerun records one trial; {len(keys)} are chosen (use --trial KEY)")
    chosen = [trial_rows(rows, k) for k in keys]  # every key checked before any replay
    replayed = []
    for trial in chosen:
        recorder = None
        if args.rerun is not None:
            from hsqbench.viz.rerun_recorder import RerunRecorder

            recorder = RerunRecorder(args.rerun)
        try:
            attempts = replay_trial(trial, config, args.attempt, recorder)
        finally:
            if recorder is not None:
                recorder.close()
        for a in attempts:
            mark = "" if a.exact else " ~"
            print(
                f"{a.key} #{a.index}: {a.recorded} -> {a.replayed}{mark} ({a.detail})", flush=True
            )
        replayed += attempts
    same = sum(a.same for a in replayed)
    for (old, new), n in sorted(Counter((a.recorded, a.replayed) for a in replayed).items()):
        print(f"  {old} -> {new}: {n}")
    print(f"{same} of {len(replayed)} replayed attempts ended as recorded")
    if args.rerun is not None:
        print(f"wrote {args.rerun}")
    return 0 if same == len(replayed) else 1
