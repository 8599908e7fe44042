"""``hsqbench replay --run RUN``: re-execute recorded grasps of a benchmark run without planning, or
(``--replan``) plan them again with the run's planner; either way compare with the record."""

from __future__ import annotations

import argparse
from collections import Counter
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    RUN_HELP,
    add_output,
    add_planner,
    add_run,
    add_set,
)

HELP = "replay a run's attempts (recorded grasps, or --replan) and compare with attempts.csv"

_EPILOG = """\
Each chosen trial is set up again from its seed and objects with the run's trial config
(run.json), and its attempts execute the grasps that attempts.csv recorded (grasp_pose,
grasp_flipped, width_m) instead of asking the planner. A packed or pile round is replayed from
its first attempt up to --attempt. With --replan the trial's planner plans again at the
recorded seed instead (a change of the planner or the perception shows). Each replayed attempt
is printed as `KEY #I: RECORDED -> REPLAYED (detail)`, then the transitions are counted.

Examples:
  hsqbench replay --run runs/quick --trial isolated/hsq/s0/mug/000
  hsqbench replay --run runs/quick --outcome dropped --limit 5 --set execution.release_height_m=0.01
  hsqbench replay --run runs/quick --trial packed/hsq/s0/003 --attempt 2 --rerun round.rrd
  hsqbench replay --run runs/quick --replan --detail "not in the bin" --limit 50 --csv turned.csv
  hsqbench replay --run runs/pile --replan --planner hsq --failed-graspable --limit 20

The replay is exact when the executed grasp was the first one motion-planned (ranks_tried 1);
otherwise the inverse kinematics draws other restarts and a borderline attempt may differ
(marked `~`); a --replan replay is exact. Runs made before attempts.csv recorded grasp poses
can only be replayed with --replan.

Exit status: 0 when every replayed attempt ended as recorded, 1 when one did not, 2 on bad
input.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    add_run(parser, f"the benchmark run to replay ({RUN_HELP})", reads=True, positional_alias=True)
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
        "--replan",
        action="store_true",
        help="plan again with the run's planner at the recorded seed (default: execute the "
        "recorded grasps)",
    )
    _add_filters(parser)
    add_set(parser, "run's trial config for the replay", "execution.release_height_m=0.01")
    add_output(
        parser,
        "csv",
        "write every replayed attempt (key, index, recorded, replayed, exact, detail)",
        dest="out",
    )
    deprecated(parser, "--out", "--csv", "out", type=Path)
    add_output(parser, "rerun", "record the replay (one trial) into this .rrd file")


def _add_filters(parser: argparse.ArgumentParser) -> None:
    """The options that choose trials when no --trial is given."""
    parser.add_argument(
        "--outcome",
        default="",
        metavar="NAME",
        help="without --trial: trials with an attempt of this outcome, e.g. dropped",
    )
    add_planner(parser, "without --trial: trials of this planner", default="")
    parser.add_argument(
        "--detail",
        default="",
        metavar="TEXT",
        help="without --trial: trials with an attempt whose detail contains TEXT",
    )
    parser.add_argument(
        "--failed-graspable",
        action="store_true",
        help="without --trial: trials with a failed attempt on a graspable presentation",
    )
    parser.add_argument(
        "--limit",
        type=int,
        default=10,
        metavar="N",
        help="without --trial: at most this many trials (default 10)",
    )


def _overrides(items: list[str]) -> dict[str, object]:
    from hsqbench.cli import CommandError
    from hsqbench.errors import ConfigError
    from hsqbench.overrides import parse_assignments

    try:
        return parse_assignments(items)
    except ConfigError as err:
        raise CommandError(str(err)) from None


def _chosen_keys(args: argparse.Namespace, rows: list[dict[str, str]]) -> list[str]:
    from hsqbench.cli import CommandError
    from hsqbench.experiment.replay import TrialFilter, select_trials

    if args.trial:
        return list(args.trial)
    chosen = TrialFilter(args.outcome, args.planner, args.detail, args.failed_graspable)
    keys = select_trials(rows, chosen)
    if not keys:
        raise CommandError(
            f"{args.run}: no finished trial matches --outcome / --planner / --detail / "
            "--failed-graspable"
        )
    if len(keys) > args.limit:
        print(f"{len(keys)} trials match; replaying the first {args.limit} (--limit)")
    return keys[: args.limit]


def _write_csv(path: Path, replayed: list) -> None:
    import csv

    path.parent.mkdir(parents=True, exist_ok=True)  # as every output's folder is made
    with path.open("w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["trial_key", "attempt_index", "recorded", "replayed", "exact", "detail"])
        for a in replayed:
            out.writerow([a.key, a.index, a.recorded, a.replayed, int(a.exact), a.detail])


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
            attempts = replay_trial(trial, config, args.attempt, recorder, args.replan)
        finally:
            if recorder is not None:
                recorder.close()
        for a in attempts:
            mark = "" if a.exact else " ~"
            print(
                f"{a.key} #{a.index}: {a.recorded} -> {a.replayed}{mark} ({a.detail})", flush=True
            )
        replayed += attempts
    if args.out is not None:
        _write_csv(args.out, replayed)
    same = sum(a.same for a in replayed)
    for (old, new), n in sorted(Counter((a.recorded, a.replayed) for a in replayed).items()):
        print(f"  {old} -> {new}: {n}")
    print(f"{same} of {len(replayed)} replayed attempts ended as recorded")
    for path in (args.out, args.rerun):
        if path is not None:
            print(f"wrote {path}")
    return 0 if same == len(replayed) else 1
