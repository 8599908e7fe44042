"""Run a protocol: build the trial list, skip what a run folder already holds, run the rest.

The runner owns the run folder (``runs/<run>/``): it checks that a resumed run has the same
config hash (:mod:`hsqbench.experiment.resume`), repairs the files after a kill (see
:mod:`hsqbench.experiment.results`), records each trial as it finishes, and shows its progress
with the running GSR per planner (a bar on a terminal, periodic plain lines in a log:
:mod:`hsqbench.experiment.progress`).
"""

from __future__ import annotations

import itertools
import sys
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from hsqbench.config import config_hash, to_dict
from hsqbench.experiment.backend import SimBackend, TrialBackend, TrialRun
from hsqbench.experiment.config import ExperimentConfig
from hsqbench.experiment.executor import Executor, SerialExecutor
from hsqbench.experiment.machine import machine_info
from hsqbench.experiment.progress import RunProgress, Tally
from hsqbench.experiment.results import RUN_FILE, ResultStore
from hsqbench.experiment.resume import check_resumable, existing_run
from hsqbench.experiment.seeds import TrialSpec, build_trials
from hsqbench.outputs import check_output
from hsqbench.planner.registry import planner_sources
from hsqbench.settings import code_version
from hsqbench.sim.outcome import Outcome


@dataclass(frozen=True)
class RunIdentity:
    """What a run's results depend on: the protocol and the backend's settings."""

    config: ExperimentConfig
    backend: dict[str, Any] = field(default_factory=dict)


@dataclass
class RunSummary:
    """What one invocation did. ``selected`` = skipped (already recorded) + ran; ``errors``:
    trials that failed with an infrastructure error; ``planner_errors``: attempts that ended in
    the planner's own error (failed attempts, in the rates), the first one's detail in
    ``first_planner_error``."""

    run_dir: Path
    config_hash: str
    selected: int
    skipped: int
    ran: int = 0
    errors: int = 0
    planner_errors: int = 0
    first_planner_error: str = ""
    interrupted: bool = False


PLANNER_ERROR = str(Outcome.PLANNER_ERROR)


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="seconds")


def protocol_objects(
    config: ExperimentConfig, experiments: Iterable[str] | None = None
) -> tuple[str, ...]:
    """The objects the chosen experiments (default: the enabled ones) use, in first-use order:
    exactly what a run must build, no more."""
    if experiments is None:
        return config.object_names()
    chosen = [e for e in config.enabled_experiments() if e in set(experiments)]
    return tuple(dict.fromkeys(o for e in chosen for o in getattr(config, e).objects))


def unusable_error(spec: TrialSpec, unusable: dict[str, str]) -> str | None:
    """Why the trial ``spec`` cannot run (an object that could not be made ready), else None."""
    bad = [o for o in spec.objects if o in unusable]
    if not bad:
        return None
    return "; ".join(f"object {o!r} cannot be used: {unusable[o]}" for o in bad) + (
        " (not run; fix the object, then --resume --retry-errors)"
    )


#: Where ``run.json`` records the draws of each round experiment.
DRAW_KEYS = {"packed": "packed_draws", "pile": "pile_draws"}


def packed_draws(
    specs: Iterable[TrialSpec], experiment: str = "packed"
) -> dict[str, dict[str, list]]:
    """The draw of each packed (or pile) round, for ``run.json``: ``s<base>/round/<index>`` ->
    the objects and the rejected draws (those that could not be placed apart, or piled)."""
    out: dict[str, dict[str, list]] = {}
    for s in specs:
        if s.experiment == experiment:
            out[f"s{s.base_seed}/round/{s.index:03d}"] = {
                "objects": list(s.objects),
                "rejected": [list(d) for d in s.rejected_draws],
            }
    return out


def run_benchmark(
    config: ExperimentConfig,
    run_dir: str | Path,
    *,
    backend: TrialBackend | None = None,
    executor: Executor | None = None,
    planners: Iterable[str] | None = None,
    experiments: Iterable[str] | None = None,
    resume: bool = False,
    force: bool = False,
    retry_errors: bool = False,
    progress: bool = True,
    config_name: str = "",
    base_seeds: Iterable[int] | None = None,
) -> RunSummary:
    """Run (or resume) the trials of ``config`` into ``run_dir``.

    Args:
        backend: runs one trial; default :class:`SimBackend` (the MuJoCo trial runner).
        executor: default in-process (:class:`SerialExecutor`).
        planners, experiments, base_seeds: run only these (the config, and so the hash, is
            unchanged, so a later ``resume`` can add the others to the same run).
        resume: continue an existing run folder (a missing folder starts a new run).
        force: move an existing run folder aside (``<name>.replaced-<UTC time>``) and start anew.
        retry_errors: when resuming, run again the trials recorded as errors.

    Raises:
        OutputPathError: ``run_dir`` cannot be a folder written by this user (a file, ...).
        ResultsError: the folder holds another config's run, or exists without ``resume``, or
            a packed round now draws other objects than recorded in ``run.json``.
        PackedDrawError: a packed round has no placeable draw within ``packed.max_draws``.
        TrialRunnerUnavailable: the default backend cannot import the trial runner.
        KeyboardInterrupt: re-raised after recording the interruption; rows written so far stay.
    """
    run_dir = check_output(run_dir, folder=True, option="run folder")  # before any work
    backend = backend if backend is not None else SimBackend(config.trial_config)
    executor = executor if executor is not None else SerialExecutor()
    store = ResultStore(run_dir)
    meta = existing_run(store, run_dir, resume, force)
    # A subset of the config's seeds (--until-halfwidth adds them); the hash keeps them all.
    chosen = config if base_seeds is None else _only_seeds(config, base_seeds)
    specs, unusable = _select(chosen, backend, executor, planners, experiments, progress)
    fingerprint = backend.fingerprint()
    if plugged := planner_sources(config.planners):  # plugins' code is part of the run's identity
        fingerprint = {**fingerprint, "planner_sources": plugged}
    chash = config_hash(RunIdentity(config, fingerprint))
    specs = list(specs)
    draws = {key: packed_draws(specs, kind) for kind, key in DRAW_KEYS.items()}
    check_resumable(
        run_dir, meta, draws, chash, {"config": to_dict(config), "backend": fingerprint}
    )

    with store.locked():
        version = code_version()
        machine = machine_info()
        if meta is None:
            meta = _new_meta(run_dir, config_name, chash, config, fingerprint, version, machine)
        _record_draws(meta, draws, progress)
        kept = store.prepare(retry_errors=retry_errors)
        pending = [s for s in specs if s.key not in store.done_keys]
        summary = RunSummary(run_dir, chash, len(specs), len(specs) - len(pending))
        session = _new_session(version, machine, executor, specs, summary, unusable)
        meta["sessions"].append(session)
        store.write_meta(meta)
        tally = Tally()
        selected_keys = {s.key for s in specs}
        tally.add(r for r in kept.attempts if r["trial_key"] in selected_keys)
        _run_pending(
            store,
            meta,
            session,
            summary,
            tally,
            pending,
            unusable,
            backend,
            executor,
            version,
            progress,
        )
    return summary


def _only_seeds(config: ExperimentConfig, base_seeds: Iterable[int]) -> ExperimentConfig:
    """``config`` restricted to those of its seeds in ``base_seeds`` (at least one)."""
    keep = tuple(s for s in config.seeds if s in set(base_seeds))
    if not keep:
        raise ValueError(
            f"base_seeds {list(base_seeds)}: none is among the config's {config.seeds}"
        )
    return replace(config, seeds=keep)


def _record_draws(meta: dict, draws: dict[str, dict], progress: bool) -> None:
    """Merge this session's packed and pile draws into ``meta``; say which rounds were redrawn."""
    redrawn = []
    for kind, key in DRAW_KEYS.items():
        if draws[key] or key in meta or kind == "packed":
            meta[key] = {**meta.get(key, {}), **draws[key]}
        redrawn += sorted(f"{kind} {k}" for k, v in draws[key].items() if v["rejected"])
    if redrawn and progress:
        print(
            f"round(s) {redrawn} redrawn: their first draws cannot be placed apart (packed) "
            f"or do not settle into a pile (pile) (packed_draws, pile_draws in {RUN_FILE}; "
            "detail in rounds.csv)",
            file=sys.stderr,
        )


def _select(
    config: ExperimentConfig,
    backend: TrialBackend,
    executor: Executor,
    planners: Iterable[str] | None,
    experiments: Iterable[str] | None,
    progress: bool,
) -> tuple[list[TrialSpec], dict[str, str]]:
    """The trials to run and the objects that cannot be used (with why), after checking the
    selection (cheaply, before any object is built) and making the objects ready."""
    first_draws = build_trials(config, planners, experiments)
    backend.check(tuple(dict.fromkeys(s.planner for s in first_draws)))
    jobs = 1 if isinstance(executor, SerialExecutor) else getattr(executor, "jobs", None)
    unusable = backend.prepare(protocol_objects(config, experiments), jobs, progress)
    for name, why in unusable.items():
        print(
            f"object {name!r} cannot be used and its trials are recorded as errors without "
            f"running: {why}",
            file=sys.stderr,
        )

    def placeable(objects: tuple[str, ...], seed: int) -> bool:
        # A draw holding an unusable object is kept (its round becomes an error record), so
        # the other rounds draw exactly what they draw when every object works.
        return not unusable.keys().isdisjoint(objects) or backend.placeable(objects, seed)

    def pile_placeable(objects: tuple[str, ...], seed: int) -> bool:
        return not unusable.keys().isdisjoint(objects) or backend.pile_placeable(objects, seed)

    specs = build_trials(config, planners, experiments, placeable, pile_placeable)
    return specs, unusable


def _new_meta(
    run_dir: Path,
    config_name: str,
    chash: str,
    config: ExperimentConfig,
    fingerprint: dict[str, Any],
    version: str,
    machine: dict[str, Any],
) -> dict[str, Any]:
    """A new run's ``run.json``: config, hash, backend settings, code version and machine."""
    return {
        "run": run_dir.name,
        "config_name": config_name,
        "config_hash": chash,
        "config": to_dict(config),
        "backend": fingerprint,
        "code_version": version,
        "created_at": _now(),
        "machine": machine,
        "sessions": [],
    }


def _new_session(
    version: str,
    machine: dict[str, Any],
    executor: Executor,
    specs: list[TrialSpec],
    summary: RunSummary,
    unusable: dict[str, str],
) -> dict[str, Any]:
    """The record of this invocation in ``run.json``'s ``sessions``."""
    return {
        "started_at": _now(),
        "code_version": version,
        "host": machine["host"],
        "machine": machine,
        "executor": executor.name,
        "jobs": getattr(executor, "jobs", None),
        "planners": list(dict.fromkeys(s.planner for s in specs)),
        "experiments": sorted({s.experiment for s in specs}),
        "trials_selected": summary.selected,
        "trials_skipped": summary.skipped,
        "unusable_objects": dict(unusable),
        "status": "running",
    }


def _run_pending(
    store: ResultStore,
    meta: dict[str, Any],
    session: dict[str, Any],
    summary: RunSummary,
    tally: Tally,
    pending: list[TrialSpec],
    unusable: dict[str, str],
    backend: TrialBackend,
    executor: Executor,
    version: str,
    progress: bool,
) -> None:
    """Run the pending trials (those with an unusable object recorded as errors without
    running), appending each as it finishes; the session's status is recorded however it ends."""
    shown = (
        RunProgress(store.run_dir.name, summary.selected, summary.skipped, tally)
        if progress
        else None
    )
    status = "failed"
    try:
        blocked = [s for s in pending if unusable_error(s, unusable)]
        runnable = [s for s in pending if not unusable_error(s, unusable)]
        recorded = (TrialRun.failed(s, unusable_error(s, unusable) or "") for s in blocked)
        ran = executor.run(backend, runnable) if runnable else ()
        for trial_run in itertools.chain(recorded, ran):
            rows = store.append(trial_run, summary.config_hash, version)
            summary.ran += 1
            summary.errors += not trial_run.ok
            broken = [r["detail"] for r in rows if r["outcome"] == PLANNER_ERROR]
            summary.planner_errors += len(broken)
            summary.first_planner_error = summary.first_planner_error or next(iter(broken), "")
            tally.add(rows)
            if shown is not None:
                shown.update()
        status = "finished"
    except KeyboardInterrupt:
        summary.interrupted = True
        status = "interrupted"
        raise
    finally:
        if shown is not None:
            shown.close()
        session.update(
            finished_at=_now(), trials_run=summary.ran, errors=summary.errors, status=status
        )
        store.write_meta(meta)
