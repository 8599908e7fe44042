"""``hsqbench sweep``: step config parameters over values and measure each planner at every point."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hsqbench.experiment.sweep_config import SweepConfig

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    PLANNER_SPEC_HELP,
    RUN_HELP,
    add_executor,
    add_experiments,
    add_jobs,
    add_planners,
    add_protocols,
    add_run,
    add_run_control,
    add_seeds,
    positive_int,
)

HELP = (
    "robustness sweeps: run a protocol at each value of config parameters (depth noise, "
    "calibration, cameras, friction, ...) and plot GSR against the value per planner"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    _add_sweeps(parser)
    _add_scope(parser)
    _add_execution(parser)


def _add_sweeps(parser: argparse.ArgumentParser) -> None:
    """What to sweep: sweep configs, or one ad hoc parameter with its protocols and experiments."""
    parser.add_argument(
        "sweeps",
        nargs="*",
        metavar="SWEEP",
        help="sweep configs: names in configs/protocols/sweeps/ (depth_noise, calibration, cameras, "
        "pad_friction) or YAML paths; or use --param and --values",
    )
    parser.add_argument(
        "--param", metavar="KEY", help="an ad hoc sweep: this config key, e.g. "
        "perception.tof.sigma_quad_per_m, robot.pads.friction.0, scene.depth_cameras.names",
    )  # fmt: skip
    parser.add_argument(
        "--values",
        nargs="+",
        metavar="VALUE",
        help="with --param: its values, each read as YAML (0.002, true, [cam_left])",
    )
    add_protocols(
        parser,
        "with --param: the protocols (default paper); with sweep configs: run only these of "
        "their protocols (e.g. ycb), keeping the others' recorded runs",
    )
    add_experiments(
        parser,
        "with --param: the experiments (default isolated)",
        ["isolated"],
    )


def _add_scope(parser: argparse.ArgumentParser) -> None:
    """What runs at each point (attempts, planners, seeds, parameters) and where results go."""
    parser.add_argument(
        "--attempts-per-object",
        type=positive_int,
        default=None,
        metavar="N",
        help="isolated attempts per object and seed at every point (overrides the sweep's)",
    )
    add_planners(
        parser,
        "run only these planners (the sweep's others can be added later to the same runs); "
        f"{PLANNER_SPEC_HELP}, which joins the sweep's list (new runs)",
    )
    add_seeds(parser, "base seeds (overrides the sweep's; more seeds: more poses, narrower bands)")
    parser.add_argument(
        "--only", nargs="+", default=None, metavar="PARAM", help="run only these parameters"
    )
    add_run(parser, f"the sweep folder ({RUN_HELP}; default runs/sweeps)", default="sweeps")


def _add_execution(parser: argparse.ArgumentParser) -> None:
    """How the sweep runs: workers, executor, what is there already, report."""
    add_jobs(parser)
    add_executor(parser)
    add_run_control(
        parser,
        "continue the sweep folder --run RUN, or add sweeps to it: finished points are reused",
    )
    deprecated(parser, "--report-only", "hsqbench report --run RUN", "report_only", flag=True)


def _sweeps(args: argparse.Namespace) -> list:
    import yaml

    from hsqbench.cli import CommandError
    from hsqbench.experiment.sweep_config import (
        SweepConfig,
        SweepParameter,
        SweepProtocol,
        load_sweep_config,
    )

    if bool(args.param) != bool(args.values):
        raise CommandError("--param and --values go together")
    if args.param and args.sweeps:
        raise CommandError("give sweep configs or --param/--values, not both")
    if not args.param and not args.sweeps:
        raise CommandError("name a sweep (e.g. depth_noise) or give --param PATH --values ...")
    if args.param:
        values = tuple(yaml.safe_load(v) for v in args.values)
        name = args.param.replace(".", "_")
        sweeps = [
            SweepConfig(
                protocols=tuple(SweepProtocol(p) for p in args.protocol or ["paper"]),
                parameters=(SweepParameter(name=name, path=args.param, values=values),),
                experiments=tuple(args.experiments),
            )
        ]
    else:
        sweeps = [load_sweep_config(s) for s in args.sweeps]
    from dataclasses import replace

    out = []
    for sweep in sweeps:
        changes = {}
        if args.protocol and not args.param:
            names = [p.name for p in sweep.protocols]
            if unknown := [p for p in args.protocol if p not in names]:
                raise CommandError(
                    f"--protocols {' '.join(unknown)}: not a protocol of sweep "
                    f"'{sweep.parameters[0].name}'; its protocols: {', '.join(names)}"
                )
            sweep = replace(
                sweep, protocols=tuple(p for p in sweep.protocols if p.name in args.protocol)
            )
        protocol_changes = {}
        if args.seeds is not None:
            # --seeds replaces every protocol's seeds too.
            changes["seeds"] = tuple(args.seeds)
            protocol_changes["seeds"] = None
        # The sweep's own planners stay its runs' identity (--planners only picks which of them
        # run, see run_planners); a planner it lacks joins the list, which means new runs.
        if extra := [p for p in args.planners or () if p not in sweep.planners]:
            changes["planners"] = (*sweep.planners, *extra)
        if args.attempts_per_object is not None:
            protocol_changes["attempts_per_object"] = args.attempts_per_object
        if protocol_changes:
            changes["protocols"] = tuple(replace(p, **protocol_changes) for p in sweep.protocols)
        if changes:
            sweep = replace(sweep, **changes)
        out.append(sweep)
    return out


def run_planners(args: argparse.Namespace, sweep: SweepConfig) -> tuple[str, ...]:
    """The planners to run now: ``--planners`` or all of the sweep's, less those whose optional
    extra is not installed (said on stderr). The sweep's planner list is left as it is, so the
    points' run folders are the same with or without them and a later run adds the rest."""
    from hsqbench.planner.registry import runnable

    return tuple(runnable(args.planners or sweep.planners))


def _existing_sweep(root: Path, args: argparse.Namespace) -> None:
    """As ``benchmark`` treats a run folder: a sweep folder that holds a sweep is continued
    only with ``--resume`` (its points' runs are named by their settings, so any sweep can be
    added to it), moved aside with ``--force``, and otherwise an error."""
    from hsqbench.cli import CommandError
    from hsqbench.experiment.resume import move_aside

    if args.retry_errors and not args.resume:
        raise CommandError("--retry-errors only applies with --resume")
    if not (root / "sweep.json").is_file() or args.resume:
        return
    if args.force:
        print(f"moved the previous sweep folder to {move_aside(root)}", file=sys.stderr)
        return
    raise CommandError(
        f"{root} already holds a sweep: pass --resume to continue it or add to it (finished "
        "points are reused), choose another --run, or --force to move it aside"
    )


def run(args: argparse.Namespace) -> int:
    from hsqbench.cli import CommandError
    from hsqbench.experiment.backend import TrialRunnerUnavailable
    from hsqbench.experiment.executor import make_executor
    from hsqbench.experiment.sweep import run_sweep
    from hsqbench.settings import RESULTS_DIR

    root = Path(args.run) if "/" in args.run else RESULTS_DIR / args.run
    if args.report_only:  # the deprecated spelling of `hsqbench report --run RUN`
        from hsqbench.commands.report import report_sweep

        report_sweep(root)
        return 0
    if args.planners:  # names, or plugin specs registered here (and in the workers)
        from hsqbench.planner.registry import resolve_planners

        args.planners = resolve_planners(args.planners)
    sweeps = _sweeps(args)
    _existing_sweep(root, args)
    executor = make_executor(args.executor, args.jobs, args.address)
    errors = 0
    try:
        for sweep in sweeps:
            summary = run_sweep(
                sweep,
                root,
                executor=executor,
                planners=run_planners(args, sweep),
                only=args.only,
                retry_errors=args.retry_errors,
                report=not args.no_report,
            )
            errors += summary.errors
    except TrialRunnerUnavailable as exc:
        raise CommandError(f"cannot run the sweep: {exc}") from exc
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: finished trials are saved under {root}; the same command with "
            "--resume continues",
            file=sys.stderr,
        )
        return 130
    if args.no_report:
        print(f"sweep: runs in {root} (its report: hsqbench report --run {root})")
    else:
        print(f"sweep: {root / 'sweep.csv'} and one PNG per parameter in {root}")
    if errors:
        print(
            f"{errors} trial(s) failed with an infrastructure error; rerun with --resume "
            "--retry-errors",
            file=sys.stderr,
        )
        return 1
    return 0
