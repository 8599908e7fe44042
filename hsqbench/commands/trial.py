"""``hsqbench trial``: run one isolated trial or one packed round in MuJoCo and print it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    PLANNER_SPEC_HELP,
    add_output,
    add_planner,
    add_scene,
    add_seed,
    add_set,
)
from hsqbench.names import check_objects

HELP = "run one grasp trial (isolated object) or one packed round in the simulator"

_EPILOG = """\
An isolated trial places --object at the seed's random upright pose and makes one attempt.
A packed round (--scene packed) places five objects (--objects, or drawn by the seed) and makes
attempts until the table is clear or two attempts in a row fail. A pile round (--scene pile) is
the same on five objects dropped into a heap.

Outcomes: success, no_grasp_found, planner_error, unreachable, collision_on_approach,
empty_grasp, dropped, sim_unstable. The same seed and config give the same outcomes.

Exit status: 0 when the trial ran (whatever its outcome), 2 on bad input, and 2 when the
planner raised or broke its contract (one line names its file and line; a benchmark counts
such an attempt as the planner's failure, planner_error).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument(
        "--object", default=None, metavar="NAME", help="object of an isolated trial"
    )
    add_seed(parser, "the trial's seed (default 0)")
    add_scene(parser, "isolated", "kind of trial: one object, or a packed or pile round")
    parser.add_argument(
        "--objects",
        nargs="+",
        default=None,
        metavar="NAME",
        help="objects of a packed round (default: drawn by the seed)",
    )
    add_planner(parser, f"{PLANNER_SPEC_HELP} (default: hsq)", default="hsq")
    parser.add_argument(
        "--trial-config",
        default=None,
        metavar="NAME",
        help="trial config: a name in configs/ or a YAML path (default: trial)",
    )
    deprecated(parser, "--config", "--trial-config", "trial_config")
    add_set(parser, "trial config", "execution.lift_height_m=0.15")
    parser.add_argument(
        "--sensor",
        choices=("cameras", "surface"),
        default=None,
        help="override the config's sensor (surface: fast stand-in without rendering)",
    )
    add_output(parser, "json", "write the result as JSON here")
    add_output(parser, "rerun", "record the episode for Rerun into this .rrd file")


def _check_names(args: argparse.Namespace) -> None:
    from hsqbench.assets.on_demand import fetch_missing
    from hsqbench.cli import CommandError
    from hsqbench.planner.registry import resolve_planner

    args.planner = resolve_planner(args.planner)  # a spec is registered; unknown: did you mean
    # YCB objects not downloaded yet are fetched first, as `benchmark` does (without HSQ_YCB_DIR).
    fetch_missing([args.object] if args.object else (args.objects or []))
    if args.scene == "isolated":
        if args.objects:
            raise CommandError("--objects is for --scene packed; use --object for one object")
        if args.object is None:
            raise CommandError(
                "--object is required for an isolated trial (`hsqbench assets list` shows them)"
            )
        wanted = [args.object]
    else:
        if args.object is not None:
            raise CommandError("--object is for isolated trials; use --objects with --scene packed")
        wanted = args.objects or []
    check_objects(wanted)


def _recorder(path: Path | None):
    """The Rerun episode recorder for ``--rerun`` (imported only when asked for)."""
    if path is None:
        return None
    from hsqbench.viz.rerun_recorder import RerunRecorder

    return RerunRecorder(path)


def _line(i: int, a) -> str:
    score = f"{a.score:.3f}" if a.score == a.score else "  -  "
    width = f"{a.width_m * 1000:3.0f} mm" if a.width_m == a.width_m else "   -  "
    return (
        f"attempt {i + 1}: {a.outcome!s:21s} target={a.target or '-':22s} rank={a.rank_executed:2d} "
        f"score={score} width={width}  perception {a.perception_s:.2f} s, planning "
        f"{a.planning_s:.2f} s, execution {a.execution_s:.2f} s  ({a.detail})"
    )


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from hsqbench.overrides import parse_assignments
    from hsqbench.planner.failure import PlannerError
    from hsqbench.sim.outcome import Outcome
    from hsqbench.sim.trial import load_trial_config, run_isolated_trial, run_packed_round

    _check_names(args)
    config = load_trial_config(args.trial_config or "trial", parse_assignments(args.set))
    if args.sensor is not None:
        config = replace(config, sensor=args.sensor)
    recorder = _recorder(args.rerun)
    try:
        if args.scene == "isolated":
            result = run_isolated_trial(
                args.object, args.seed, args.planner, config, recorder=recorder
            )
        else:
            result = run_packed_round(
                args.objects, args.seed, args.planner, config, recorder=recorder, kind=args.scene
            )
    finally:
        if recorder is not None:
            recorder.close()
    broken = [a.detail for a in result.attempts if a.outcome == Outcome.PLANNER_ERROR]
    if broken:  # the planner's own code failed: one line where it did, as for bad input
        raise PlannerError(broken[0])
    for i, a in enumerate(result.attempts):
        print(_line(i, a))
    if args.scene == "isolated":
        print(
            f"isolated trial: {result.object}, seed {result.seed}, planner {result.planner}: "
            f"{'success' if result.success else 'failure'}"
        )
    else:
        n_ok = sum(a.success for a in result.attempts)
        print(
            f"{args.scene} round, seed {result.seed}, planner {result.planner}: grasps "
            f"{n_ok}/{len(result.attempts)} successful, cleared {len(result.objects_cleared)}/"
            f"{result.objects_presented} ({', '.join(result.objects_cleared) or 'none'}) of "
            f"{', '.join(result.objects)}"
        )
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(result.to_dict(), indent=2) + "\n")
        print(f"wrote {args.json}")
    if args.rerun is not None:
        print(f"wrote {args.rerun}")
    return 0
