"""Run a sweep: every point of every parameter on every protocol, each an ordinary run folder.

Layout of a sweep folder (default ``runs/sweeps/``)::

    sweep.json                      the parameters run into this folder, their points and runs
    sweep.csv                       one row per protocol, experiment, parameter, point, planner
    <parameter>.png                 GSR (and CR for packed) against the point, a line per planner
    runs/<protocol>/<slug>-<hash>/  one run per distinct setting (attempts.csv, run.json, ...)

A point's run folder is named by what its results depend on (the protocol at the sweep's size
and the overrides), so points with the same settings share one run: the protocol's own settings
(empty overrides) are run once for all parameters of a folder. Rerunning a sweep (``--resume``)
resumes every run (finished trials are skipped, :func:`hsqbench.experiment.runner.run_benchmark`); a sweep with
other sizes or seeds runs into new folders. All points run the same trials (same seeds, same
poses), so two points differ only by their settings.
"""

from __future__ import annotations

import json
import re
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from hsqbench.config import config_hash, to_dict
from hsqbench.experiment.backend import SimBackend, TrialBackend
from hsqbench.experiment.config import ExperimentConfig, load_experiment_config
from hsqbench.experiment.executor import Executor
from hsqbench.experiment.runner import RunSummary, run_benchmark
from hsqbench.experiment.sweep_config import SweepConfig, SweepParameter, SweepProtocol

SWEEP_FILE = "sweep.json"
CSV_FILE = "sweep.csv"
MARKDOWN_FILE = "sweep.md"
RUNS_DIR = "runs"

#: Makes the backend of a point: (trial config name, overrides) -> backend.
BackendFactory = Callable[[str, dict[str, Any]], TrialBackend]


def sim_backend(trial_config: str, overrides: dict[str, Any]) -> TrialBackend:
    return SimBackend(trial_config, overrides=tuple(overrides.items()))


def point_config(protocol: SweepProtocol, sweep: SweepConfig) -> ExperimentConfig:
    """The protocol at the sweep's size: its planners, seeds (the protocol's own, else the
    sweep's), attempts and rounds, with only the sweep's experiments enabled."""
    base = load_experiment_config(protocol.config)
    # The objects are resolved names already (``exclude`` applied), so it is emptied.
    iso, pk = base.isolated, base.packed
    isolated = replace(
        iso,
        exclude=(),
        enabled=iso.enabled and "isolated" in sweep.experiments,
        attempts_per_object=protocol.attempts_per_object or iso.attempts_per_object,
    )
    packed = replace(
        pk,
        exclude=(),
        enabled=pk.enabled and "packed" in sweep.experiments,
        rounds=protocol.rounds or pk.rounds,
    )
    pile = base.pile
    if pile.enabled or "pile" in sweep.experiments:  # untouched otherwise: the runs' hashes stay
        pile = replace(
            pile,
            exclude=(),
            enabled=pile.enabled and "pile" in sweep.experiments,
            rounds=protocol.rounds or pile.rounds,
        )
    if not (isolated.enabled or packed.enabled or pile.enabled):
        raise ValueError(
            f"protocol {protocol.config!r} enables none of the sweep's experiments "
            f"{list(sweep.experiments)}"
        )
    return replace(
        base,
        planners=sweep.planners,
        seeds=protocol.seeds or sweep.seeds,
        isolated=isolated,
        packed=packed,
        pile=pile,
    )


def _slug(overrides: dict[str, Any]) -> str:
    if not overrides:
        return "default"
    text = "_".join(f"{k.split('.')[-1]}={v}" for k, v in overrides.items())
    text = re.sub(r"[^A-Za-z0-9_.=+-]+", "", text.replace(" ", ""))
    return text[:60] or "point"


def point_dir(
    root: Path, protocol: SweepProtocol, config: ExperimentConfig, overrides: dict
) -> Path:
    """The run folder of a setting: readable slug plus the hash of what results depend on."""
    key = config_hash(_Key(to_dict(config), overrides))[:8]
    return root / RUNS_DIR / protocol.name / f"{_slug(overrides)}-{key}"


@dataclass(frozen=True)
class _Key:
    config: dict[str, Any]
    overrides: dict[str, Any]


@dataclass
class SweepSummary:
    """What one invocation did: the runs it visited (each once) and their summaries."""

    root: Path
    runs: dict[Path, RunSummary]

    @property
    def errors(self) -> int:
        return sum(s.errors for s in self.runs.values())


def _atomic_write(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text)
    tmp.replace(path)


def _record(
    root: Path,
    sweep: SweepConfig,
    parameters: Iterable[SweepParameter],
    dirs: dict,
    configs: dict[str, ExperimentConfig],
) -> None:
    """Merge these parameters (with their points' run folders) into ``sweep.json``.

    A parameter recorded before with the same points keeps the runs of the protocols this sweep
    leaves out (``hsqbench sweep NAME --protocols ycb``), so protocols can be run one at a time.
    Each protocol is recorded with the seeds it ran.
    """
    path = root / SWEEP_FILE
    meta = json.loads(path.read_text()) if path.exists() else {"parameters": {}}
    mine = {proto.name for proto in sweep.protocols}
    for param in parameters:
        kept, kept_runs = _others(meta["parameters"].get(param.name), param, mine)
        meta["parameters"][param.name] = {
            "axis": param.axis,
            "categorical": param.categorical,
            "experiments": list(sweep.experiments),
            "planners": list(sweep.planners),
            "seeds": list(sweep.seeds),
            "protocols": kept
            + [{**to_dict(p), "seeds": list(configs[p.name].seeds)} for p in sweep.protocols],
            "points": [
                {
                    "label": point.label,
                    "x": point.x,
                    "overrides": point.overrides,
                    "runs": {
                        **kept_runs[i],
                        **{
                            proto.name: str(dirs[param.name, i, proto.name].relative_to(root))
                            for proto in sweep.protocols
                        },
                    },
                }
                for i, point in enumerate(param.points)
            ],
        }
    _atomic_write(path, json.dumps(meta, indent=2, sort_keys=True) + "\n")


def _others(
    old: dict | None, param: SweepParameter, mine: set[str]
) -> tuple[list[dict], list[dict]]:
    """The recorded protocols of ``param`` other than ``mine``, and their runs per point: none
    when the record is of other points."""
    points = [(point.label, point.overrides) for point in param.points]
    if old is None or [(p["label"], p["overrides"]) for p in old["points"]] != points:
        return [], [{} for _ in points]
    protocols = [p for p in old["protocols"] if SweepProtocol(p["config"]).name not in mine]
    runs = [{k: v for k, v in p["runs"].items() if k not in mine} for p in old["points"]]
    return protocols, runs


def run_sweep(
    sweep: SweepConfig,
    root: str | Path,
    *,
    executor: Executor | None = None,
    backend_factory: BackendFactory = sim_backend,
    planners: Iterable[str] | None = None,
    only: Iterable[str] | None = None,
    retry_errors: bool = False,
    progress: bool = True,
    report: bool = True,
) -> SweepSummary:
    """Run (or resume) every point of ``sweep`` into ``root``; then write its CSV and plots.

    Args:
        planners: run only these of the sweep's planners (the runs' hashes are unchanged, so a
            later call can add the others).
        only: run only the parameters with these names.
        report: write ``sweep.csv`` and the plots afterwards (of every parameter in the folder).
    """
    root = Path(root)
    params = _selected_parameters(sweep, only)
    configs = {proto.name: point_config(proto, sweep) for proto in sweep.protocols}
    dirs = {
        (param.name, i, proto.name): point_dir(root, proto, configs[proto.name], point.overrides)
        for param in params
        for i, point in enumerate(param.points)
        for proto in sweep.protocols
    }
    backends = _point_backends(sweep, params, dirs, configs, backend_factory, planners)
    root.mkdir(parents=True, exist_ok=True)
    _record(root, sweep, params, dirs, configs)
    todo = list(dict.fromkeys(dirs.values()))
    summary = SweepSummary(root, {})
    start = time.perf_counter()
    for param in params:
        for i, point in enumerate(param.points):
            for proto in sweep.protocols:
                run_dir = dirs[param.name, i, proto.name]
                if run_dir in summary.runs:
                    continue
                if progress:
                    done = len(summary.runs)
                    spent = time.perf_counter() - start
                    ran = sum(s.ran for s in summary.runs.values())
                    # Runs of a sweep differ in size by protocol only: a rough estimate.
                    left = (
                        f", about {_elapsed(spent / done * (len(todo) - done))} left" if ran else ""
                    )
                    print(
                        f"sweep [{done + 1}/{len(todo)}] {param.name} = {point.label} on "
                        f"{proto.name} ({_elapsed(spent)} so far{left}): {run_dir}",
                        file=sys.stderr,
                    )
                config = configs[proto.name]
                summary.runs[run_dir] = run_benchmark(
                    config,
                    run_dir,
                    backend=backends[run_dir],
                    executor=executor,
                    planners=planners,
                    experiments=sweep.experiments,
                    resume=True,
                    retry_errors=retry_errors,
                    progress=progress,
                    config_name=proto.config,
                )
    if report:
        write_sweep_report(root)
    return summary


def _selected_parameters(sweep: SweepConfig, only: Iterable[str] | None) -> list[SweepParameter]:
    """The sweep's parameters, or those named in ``only`` (an unknown name is an error)."""
    params = list(sweep.parameters)
    if only is not None:
        wanted = list(only)
        unknown = sorted(set(wanted) - {p.name for p in params})
        if unknown:
            raise ValueError(
                f"no sweep parameter(s) {unknown}; this sweep has {[p.name for p in params]}"
            )
        params = [p for p in params if p.name in wanted]
    return params


def _point_backends(
    sweep: SweepConfig,
    params: list[SweepParameter],
    dirs: dict[tuple[str, int, str], Path],
    configs: dict[str, ExperimentConfig],
    backend_factory: BackendFactory,
    planners: Iterable[str] | None,
) -> dict[Path, TrialBackend]:
    """One checked backend per run folder; a bad path or planner fails here, before any write."""
    backends: dict[Path, TrialBackend] = {}
    for param in params:
        for i, point in enumerate(param.points):
            for proto in sweep.protocols:
                run_dir = dirs[param.name, i, proto.name]
                if run_dir not in backends:
                    trial_config = configs[proto.name].trial_config
                    backends[run_dir] = backend_factory(trial_config, point.overrides)
                    # a bad path or planner fails here, before anything is written
                    backends[run_dir].check(tuple(planners or sweep.planners))
    return backends


def _elapsed(seconds: float) -> str:
    return f"{int(seconds // 60)} min {int(seconds % 60):02d} s"


def write_sweep_report(root: str | Path) -> list[Path]:
    """``sweep.csv``, ``sweep.md`` and one PNG per parameter from the runs recorded in
    ``sweep.json``."""
    from hsqbench.experiment.sweep_markdown import sweep_markdown
    from hsqbench.experiment.sweep_plot import plot_parameter
    from hsqbench.experiment.sweep_table import sweep_table

    root = Path(root)
    path = root / SWEEP_FILE
    if not path.exists():
        raise FileNotFoundError(f"{root}: no {SWEEP_FILE}; give the folder of a sweep")
    meta = json.loads(path.read_text())
    table = sweep_table(root, meta)
    written = [root / CSV_FILE]
    tmp = root / f".{CSV_FILE}.tmp"
    table.to_csv(tmp, index=False, float_format="%.4g")
    tmp.replace(written[0])
    written.append(root / MARKDOWN_FILE)
    tmp = root / f".{MARKDOWN_FILE}.tmp"
    tmp.write_text(sweep_markdown(table, meta))
    tmp.replace(written[-1])
    for name, param in meta["parameters"].items():
        rows = table[table["parameter"] == name]
        if len(rows):
            png = root / f"{name}.png"
            plot_parameter(rows, param, png)
            written.append(png)
    return written
