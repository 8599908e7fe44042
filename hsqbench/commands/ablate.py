"""``hsqbench ablate``: the benchmark with hsq, hsq-paper and hsq with each addition off.

It only builds the planner list (``hsq``, ``hsq-paper``, ``hsq-no-<addition>`` for each chosen
addition of :mod:`hsqbench.planner.hsq.additions`, plus any ``--planners`` baselines) and runs the
protocol's experiments with it through the benchmark runner, into runs/<run>/ with the usual
tables: each row against ``hsq`` is what that addition buys.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    PLANNER_SPEC_HELP,
    RUN_HELP,
    add_executor,
    add_experiments,
    add_jobs,
    add_planners,
    add_protocol,
    add_run,
    add_run_control,
    add_seeds,
    protocol_of,
)

HELP = "run a protocol with hsq, hsq-paper and hsq with each of our additions off in turn"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_protocol(parser)
    add_run(parser, f"the run folder: {RUN_HELP} (default ablate-<protocol>-<UTC time>)")
    parser.add_argument(
        "--additions",
        nargs="+",
        default=None,
        metavar="NAME",
        help="only these additions (default: each that is on and not superseded; see "
        "configs/planner.yaml additions:)",
    )
    add_planners(
        parser,
        f"other planners to run alongside, e.g. antipodal: {PLANNER_SPEC_HELP}",
        dest="extra",
    )
    deprecated(parser, "--with", "--planners", "extra", nargs="+")
    add_seeds(parser, "base seeds instead of the protocol's (a run of its own)")
    add_jobs(parser)
    add_executor(parser)
    add_experiments(parser)
    add_run_control(parser, "continue the run --run RUN: finished trials are skipped")


def ablation_planner_list(additions: list[str] | None, extra: tuple[str, ...] = ()) -> list[str]:
    """``hsq``, ``hsq-paper``, then ``hsq-no-<name>`` per addition (default: each one that is on
    in ``configs/planner.yaml``, less those superseded by another that is on, whose planner would
    plan as hsq in every trial; each is left out with a line on stderr), then ``extra``.

    Raises:
        ValueError: an unknown addition, or one that is off by default (``hsq-no-<name>`` would
            be hsq itself); the message lists the choices.
    """
    import sys

    from hsqbench.planner.hsq.additions import ADDITIONS, AdditionsConfig, planner_name
    from hsqbench.planner.hsq.config import load_planner_config

    known = AdditionsConfig.names()
    off = load_planner_config().additions.off()
    on = [a for a in known if a not in off]
    if additions is None:
        chosen = []
        for name in on:
            by = ADDITIONS[name].superseded_by
            if by is not None and by in on:
                print(
                    f"leaving out {planner_name(name)}: {by} takes its place where the cameras "
                    f"are known, so it would plan as hsq in every trial (name it with "
                    f"--additions {name} to run it anyway)",
                    file=sys.stderr,
                )
            else:
                chosen.append(name)
    else:
        chosen = list(additions)
    unknown = [a for a in chosen if a not in known]
    if unknown:
        raise ValueError(f"unknown addition(s) {unknown}; known: {', '.join(known)}")
    already = [a for a in chosen if a in off]
    if already:
        raise ValueError(
            f"addition(s) {already} are off in configs/planner.yaml already (hsq-no-<name> "
            f"would be hsq); on: {', '.join(on)}"
        )
    names = ["hsq", "hsq-paper", *(planner_name(a) for a in chosen), *extra]
    return list(dict.fromkeys(names))


def run(args: argparse.Namespace) -> int:
    import sys

    from hsqbench.cli import CommandError
    from hsqbench.experiment.backend import TrialRunnerUnavailable
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.experiment.executor import make_executor
    from hsqbench.experiment.runner import run_benchmark
    from hsqbench.runs import run_folder

    if args.retry_errors and not args.resume:
        raise CommandError("--retry-errors only applies with --resume --run RUN")
    if args.resume and args.run is None:
        raise CommandError("--resume needs --run RUN (the run to continue)")
    from hsqbench.planner.registry import resolve_planners

    protocol = protocol_of(args)
    planners = ablation_planner_list(args.additions, tuple(resolve_planners(args.extra or ())))
    config = dataclasses.replace(load_experiment_config(protocol), planners=tuple(planners))
    if args.seeds is not None:
        config = dataclasses.replace(config, seeds=tuple(args.seeds))
    run_dir = run_folder(args.run, f"ablate-{Path(protocol).stem}")
    print(f"run folder: {run_dir}; planners: {', '.join(planners)}", file=sys.stderr)
    try:
        summary = run_benchmark(
            config,
            run_dir,
            executor=make_executor(args.executor, args.jobs, args.address),
            experiments=args.experiments,
            resume=args.resume,
            force=args.force,
            retry_errors=args.retry_errors,
            config_name=f"{protocol} (ablation)",
        )
    except TrialRunnerUnavailable as exc:
        raise CommandError(f"cannot run the ablation: {exc}") from exc
    from hsqbench.commands.benchmark import print_summary

    print_summary(run_dir, summary, report=not args.no_report)
    return 1 if summary.errors else 0
