"""``hsqbench benchmark``: run the paper's experiments (or any protocol config) into runs/<run>/."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    PLANNER_SPEC_HELP,
    RUN_HELP,
    add_executor,
    add_experiments,
    add_jobs,
    add_output,
    add_planners,
    add_protocol,
    add_run,
    add_run_control,
    add_seeds,
    positive_int,
    protocol_of,
    register_output,
)

if TYPE_CHECKING:
    from hsqbench.experiment.config import ExperimentConfig
    from hsqbench.experiment.runner import RunSummary

HELP = "run the experiments of a benchmark protocol with its planners (or yours) into runs/<run>/"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_protocol(parser)
    add_run(parser, f"the run folder: {RUN_HELP} (default <protocol>-<UTC time>)")
    add_jobs(parser)
    add_executor(parser)
    add_planners(
        parser,
        "run these planners on the protocol's scenes (default: the protocol's own): "
        f"{PLANNER_SPEC_HELP}. One the protocol lacks joins its planner list (a run of its own)",
    )
    add_seeds(
        parser,
        "base seeds instead of the protocol's (a run of its own; more seeds: more poses, "
        "narrower intervals)",
    )
    add_experiments(parser)
    add_run_control(
        parser, "continue the run --run RUN: finished trials are skipped (a new name starts a run)"
    )
    _add_until_arguments(parser)
    _add_rerun_arguments(parser)


def _add_rerun_arguments(parser: argparse.ArgumentParser) -> None:
    """--rerun and what it records."""
    add_output(
        parser,
        "rerun",
        "after the run, record trials for Rerun into the folder PATH, one .rrd each (replayed "
        "from their seeds)",
        dest="rerun_dir",
    )
    deprecated(parser, "--rerun-dir", "--rerun", "rerun_dir", type=Path)
    register_output(parser, "rerun_dir", "--rerun", folder=True)  # a folder, though named PATH
    parser.add_argument(
        "--rerun-which",
        choices=("failures", "all"),
        default="failures",
        help="which trials --rerun records (default: failures)",
    )
    parser.add_argument(
        "--rerun-trial",
        action="append",
        default=None,
        metavar="KEY",
        help="record this trial key (as in attempts.csv) instead; repeatable",
    )


def _add_until_arguments(parser: argparse.ArgumentParser) -> None:
    """--until-halfwidth and its seed cap (:mod:`hsqbench.experiment.until_halfwidth`)."""
    parser.add_argument(
        "--until-halfwidth",
        type=float,
        default=None,
        metavar="H",
        help="add base seeds (after the protocol's) until every planner's GSR interval is at most "
        "±H (e.g. 0.02), or --max-seeds is reached; recorded in run.json. Resume with the same "
        "two options",
    )
    parser.add_argument(
        "--max-seeds",
        type=positive_int,
        default=10,
        metavar="N",
        help="with --until-halfwidth: at most N base seeds in all (default 10)",
    )


def run(args: argparse.Namespace) -> int:
    import dataclasses
    import sys

    from hsqbench.cli import CommandError
    from hsqbench.experiment.backend import TrialRunnerUnavailable
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.experiment.executor import make_executor
    from hsqbench.runs import protocol_planners, run_folder

    if args.retry_errors and not args.resume:
        raise CommandError("--retry-errors only applies with --resume --run RUN")
    if args.resume and args.run is None:
        raise CommandError("--resume needs --run RUN (the run to continue)")
    protocol = args.protocol = protocol_of(args)
    own = load_experiment_config(protocol)
    config, planners = protocol_planners(own, args.planners)
    if args.seeds is not None:
        config = dataclasses.replace(config, seeds=tuple(args.seeds))
    run_dir = run_folder(args.run, protocol)
    if args.resume:
        _check_resumed_planners(run_dir, config.planners, own.planners, planners)
    executor = make_executor(args.executor, args.jobs, args.address)
    print(f"run folder: {run_dir}", file=sys.stderr)
    try:
        summary = _run_trials(args, config, run_dir, executor, planners)
    except TrialRunnerUnavailable as exc:
        raise CommandError(f"cannot run the benchmark: {exc}") from exc
    except KeyboardInterrupt:
        print(
            f"\ninterrupted: finished trials are saved in {run_dir}; continue with\n"
            f"  hsqbench benchmark --protocol {protocol} --run {run_dir} --resume"
            + (f" --planners {' '.join(args.planners)}" if args.planners else "")
            + (f" --seeds {' '.join(map(str, args.seeds))}" if args.seeds is not None else "")
            + (
                f" --until-halfwidth {args.until_halfwidth} --max-seeds {args.max_seeds}"
                if args.until_halfwidth is not None
                else ""
            ),
            file=sys.stderr,
        )
        return 130
    print_summary(run_dir, summary, report=not args.no_report)
    if args.rerun_dir is not None:
        _record_episodes(run_dir, args)
    if summary.errors:
        print(
            f"{summary.errors} trial(s) failed with an infrastructure error (see the detail "
            "column of attempts.csv); fix the cause and rerun them with --resume --retry-errors",
            file=sys.stderr,
        )
        return 1
    return 0


def _check_resumed_planners(
    run_dir: Path, planners: tuple[str, ...], own: tuple[str, ...], named: list[str]
) -> None:
    """A resumed run keeps its planner list (the protocol's own, ``own``, and those its
    ``--planners`` added): refuse another, naming the planners the run holds trials of and the
    ``--planners`` that resume it (those, and any added one that has not run yet)."""
    import json

    from hsqbench.cli import CommandError

    path = run_dir / "run.json"
    if not path.is_file():
        return
    meta = json.loads(path.read_text())
    recorded = tuple(meta.get("config", {}).get("planners", ()))
    if not recorded or recorded == planners:
        return
    held = _held_planners(run_dir, meta) or set(recorded)
    holds = [p for p in recorded if p in held] + sorted(held - set(recorded))
    sources = meta.get("backend", {}).get("planner_sources", {})
    given = [
        sources[p]["spec"] if sources.get(p, {}).get("kind") == "file" else p
        for p in recorded
        if p in held or p not in own
    ]
    how = f"--planners {' '.join(given)}" if given else "no --planners"
    raise CommandError(
        f"{run_dir} holds trials of {', '.join(holds)} (planner list {', '.join(recorded)}); "
        f"this command runs {', '.join(named)} (planner list {', '.join(planners)}): resume it "
        f"with {how} (or start another --run)"
    )


def _held_planners(run_dir: Path, meta: dict[str, Any]) -> set[str]:
    """The planners ``run_dir`` holds finished trials of, else those its sessions ran."""
    from hsqbench.experiment.results import load_results

    held = {r["planner"] for r in load_results(run_dir).attempts}
    return held or {p for s in meta.get("sessions", []) for p in s.get("planners", [])}


def _run_trials(
    args: argparse.Namespace,
    config: ExperimentConfig,
    run_dir: Path,
    executor: Any,
    planners: tuple[str, ...] | list[str],
) -> RunSummary:
    """Run the protocol's trials, or with ``--until-halfwidth`` seed after seed."""
    from hsqbench.experiment.runner import run_benchmark

    forcing = [args.force]  # --force moves an old run aside once, never a step's own results

    def run_seeds(
        cfg: ExperimentConfig, base_seeds: tuple[int, ...] | None, resume: bool
    ) -> RunSummary:
        force, forcing[0] = forcing[0], False
        return run_benchmark(
            cfg,
            run_dir,
            executor=executor,
            planners=planners,
            experiments=args.experiments,
            resume=resume,
            force=force,
            retry_errors=args.retry_errors,
            config_name=args.protocol,
            base_seeds=base_seeds,
        )

    if args.until_halfwidth is None:
        return run_seeds(config, None, args.resume)
    from hsqbench.experiment.until_halfwidth import run_until_halfwidth

    return run_until_halfwidth(
        config, run_dir, args.until_halfwidth, args.max_seeds, run_seeds, args.resume
    )


def print_summary(run_dir: Path, summary: RunSummary, report: bool) -> None:
    """The run's one-line summary, then its tables and plots unless ``report`` is False (shared
    by ``benchmark`` and ``ablate``); a note on stderr when attempts ended in their planner's
    own error."""
    import sys

    print(
        f"{run_dir}: {summary.selected} trials selected, {summary.skipped} already done, "
        f"{summary.ran} run, {summary.errors} errors (config hash {summary.config_hash})"
    )
    if summary.planner_errors:  # failed attempts of their planner, counted in the rates
        print(
            f"{summary.planner_errors} attempt(s) ended in the planner's own error "
            f"(planner_error, counted as failures; attempts.csv detail), the first: "
            f"{summary.first_planner_error}",
            file=sys.stderr,
        )
    if report:
        from hsqbench.experiment.report import write_report

        written = write_report(run_dir)
        print(f"report: {run_dir / 'tables.md'} (+{len(written) - 1} files)")


def _record_episodes(run_dir: Path, args: argparse.Namespace) -> None:
    """Replay chosen trials with the Rerun recorder; trials are deterministic per seed."""
    from hsqbench.viz.episodes import record_run

    def show(episode) -> None:
        if episode.matches:
            print(f"recorded {episode.path}")
        else:
            print(
                f"recorded {episode.path} BUT the replay differs: "
                f"run {episode.choice.outcomes}, replay {episode.outcomes}"
            )

    record_run(run_dir, args.rerun_dir, args.rerun_which, keys=args.rerun_trial, report=show)
