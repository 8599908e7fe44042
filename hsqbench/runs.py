"""What the CLI does, from Python: run a trial, run a benchmark, load a run as pandas frames.

    import hsqbench
    trial = hsqbench.run_trial("foam_brick", planner="examples/topdown.py:TopDown", seed=3)
    run = hsqbench.run_benchmark("quick", planners=["examples/topdown.py:TopDown", "hsq"],
                                 run="runs/mine", experiments=["isolated"], jobs=2)
    run.attempts.groupby("planner")["success"].mean()

A planner is a name (``hsqbench planners``), a plugin spec (``module:Name``,
``path/to/file.py:Name``) or, for :func:`run_trial` and :func:`run_benchmark` with ``jobs=1``,
a planner class or object defined right here (a notebook cell): worker processes cannot import
those, so put the class in a file and pass its spec to run in parallel. See docs/python-api.md.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from hsqbench.experiment.config import ExperimentConfig
from hsqbench.experiment.report import RunData, load_run
from hsqbench.sim.outcome import RoundResult, TrialResult

__all__ = ["RunData", "load_run", "run_benchmark", "run_trial"]


def _planner_name(planner: Any, in_process: bool) -> str:
    """The registry name of ``planner``: a name or spec as given, a class or object of this
    process registered under its ``name`` (only when trials run in this process)."""
    from hsqbench.planner.registry import register_planner, resolve_planner

    if isinstance(planner, str):
        return resolve_planner(planner)
    name = getattr(planner, "name", None)
    if not isinstance(name, str) or not name:
        raise ValueError(f"planner {planner!r} needs a `name` (a non-empty string)")
    if not in_process:
        raise ValueError(
            f"planner {name!r} is defined in this process, which worker processes cannot import: "
            "run with jobs=1, or put it in a file and pass 'path/to/file.py:ClassName'"
        )
    from hsqbench.planner.plugins import factory

    build = (
        factory(planner, repr(name)) if inspect.isclass(planner) else lambda config=None: planner
    )
    register_planner(name, build, replace=True)
    return name


def protocol_planners(
    config: ExperimentConfig, chosen: list[str] | None
) -> tuple[ExperimentConfig, list[str]]:
    """The protocol and the planners to run: ``chosen`` (names or plugin specs) or the
    protocol's own, less optional ones whose extra is missing (said on stderr). A chosen planner
    the protocol lacks joins its list (as in ``sweep``): the run's identity then names it, and
    ``report --join`` joins this run to another of the same protocol."""
    import dataclasses

    from hsqbench.planner.registry import resolve_planners, runnable

    if chosen is None:
        return config, runnable(config.planners)
    planners = resolve_planners(chosen)
    if extra := [p for p in planners if p not in config.planners]:
        config = dataclasses.replace(config, planners=(*config.planners, *extra))
    return config, planners


def run_folder(run: str | None, protocol: str) -> Path:
    """The run folder: ``run`` (a name under ``runs/``, or a path), else
    ``runs/<protocol>-<UTC time>``."""
    from datetime import UTC, datetime

    from hsqbench.settings import RESULTS_DIR

    if run is None:
        stem = Path(protocol).stem if protocol.endswith((".yaml", ".yml")) else protocol
        return RESULTS_DIR / f"{stem}-{datetime.now(UTC).strftime('%Y%m%d-%H%M%S')}"
    if "/" in run or run in (".", ".."):
        return Path(run)
    return RESULTS_DIR / run


def run_trial(
    object: str | None = None,
    *,
    planner: Any = "hsq",
    seed: int = 0,
    scene: str = "isolated",
    objects: Sequence[str] | None = None,
    trial_config: str | Path = "trial",
    recording: str | Path | None = None,
) -> TrialResult | RoundResult:
    """One trial, as ``hsqbench trial``: an isolated ``object`` at the seed's pose, or a packed
    or pile round (``scene``) of ``objects`` (drawn by the seed when None).

    Args:
        planner: a name, a spec, or a planner class or object of this process.
        recording: write the episode for Rerun here (``hsqbench view`` opens it).

    Returns:
        the :class:`~hsqbench.sim.outcome.TrialResult` (or ``RoundResult``): its ``attempts``
        hold each attempt's outcome, grasp and timings; ``to_dict()`` is JSON-ready.

    Raises:
        ValueError: an unknown planner, object or scene (with the closest name).
    """
    from hsqbench.assets.on_demand import fetch_missing
    from hsqbench.experiment.config import EXPERIMENTS as SCENES
    from hsqbench.names import check_objects
    from hsqbench.sim.trial import load_trial_config, run_isolated_trial, run_packed_round

    if scene not in SCENES:
        raise ValueError(f"scene must be one of {list(SCENES)}, got {scene!r}")
    if (scene == "isolated") != (object is not None) or (scene == "isolated" and objects):
        raise ValueError("give object= for an isolated trial, objects= (or none) for a round")
    named = [object] if object is not None else list(objects or ())
    fetch_missing(named)  # YCB objects not downloaded yet, as `hsqbench trial` does
    check_objects(named)
    name = _planner_name(planner, in_process=True)
    config = load_trial_config(trial_config)
    recorder = None
    if recording is not None:
        from hsqbench.viz.rerun_recorder import RerunRecorder

        recorder = RerunRecorder(Path(recording))
    try:
        if scene == "isolated":
            return run_isolated_trial(object, seed, name, config, recorder=recorder)
        chosen = list(objects) if objects else None
        return run_packed_round(chosen, seed, name, config, recorder=recorder, kind=scene)
    finally:
        if recorder is not None:
            recorder.close()


def run_benchmark(
    protocol: str | Path = "quick",
    *,
    planners: Sequence[Any] | None = None,
    run: str | Path | None = None,
    experiments: Sequence[str] | None = None,
    jobs: int = 1,
    resume: bool = False,
    force: bool = False,
    report: bool = True,
    progress: bool = True,
) -> RunData:
    """A protocol's trials for ``planners`` into a run folder, as ``hsqbench benchmark``;
    returns the run loaded (:func:`load_run`).

    Args:
        protocol: ``paper``, ``quick``, ... (``configs/``) or a YAML path.
        planners: names, specs or (with ``jobs=1``) planner classes or objects of this process;
            default the protocol's own. One the protocol lacks joins its list.
        run: the run folder (a name goes under ``runs/``); default ``<protocol>-<UTC time>``.
        experiments: only these (``isolated``, ``packed``, ``pile``).
        jobs: worker processes (1: this process).
        resume, force: continue the run in ``run``, or move it aside and start anew.
        report: write ``tables.md`` and the plots into the run folder.
    """
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.experiment.executor import make_executor
    from hsqbench.experiment.runner import run_benchmark as run_protocol
    from hsqbench.names import check_protocol

    check_protocol(protocol)
    chosen = None if planners is None else [_planner_name(p, jobs == 1) for p in planners]
    config, names = protocol_planners(load_experiment_config(protocol), chosen)
    run_dir = run_folder(None if run is None else str(run), str(protocol))
    run_protocol(
        config,
        run_dir,
        executor=make_executor("local", jobs),
        planners=names,
        experiments=experiments,
        resume=resume,
        force=force,
        progress=progress,
        config_name=str(protocol),
    )
    if report:
        from hsqbench.experiment.report import write_report

        write_report(run_dir)
    return load_run(run_dir)
