"""`make results`: (re)make the canonical runs behind the README's tables and plots.

The list is ``configs/canonical.yaml``: one benchmark run per protocol config, with every planner
of that protocol, and the robustness sweeps. Each run goes to ``<out>/<name>/`` and resumes what
is there, so a killed ``make results`` loses nothing; a run folder made by other code or another
config is refused by the runner (move it aside, or ``--force`` through ``hsqbench benchmark``).

Unlike ``hsqbench benchmark``, a canonical run does not leave out a planner whose optional extra
is missing: the tables would lack a row, so it stops first and says which extra to install.

A finished run's ``attempts.csv`` is stored gzipped (``attempts.csv.gz``, byte-reproducible: no
name or time in its header; in pieces ``attempts.csv.gz.00``, ... where it would pass 2 MiB):
the committed runs stay a few MB, and every reader takes either form. The next ``make results``
unpacks it, resumes (nothing to do when complete) and packs again.

    python -m hsqbench.experiment.canonical [--out results] [--only paper3 ...] [--jobs N]
    python -m hsqbench.experiment.canonical --protocol quick --out /tmp/x   # the logic, fast
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from hsqbench.config import ConfigError, from_dict, load_config_data
from hsqbench.settings import REPO_ROOT

#: The canonical list (a name in ``configs/`` or a path).
CANONICAL = "canonical"


@dataclass(frozen=True)
class CanonicalRun:
    """One benchmark run: ``config``'s planners (or ``planners``: names or plugin specs, as
    ``hsqbench benchmark --planners`` takes them) and ``experiments`` into ``<out>/<name>``."""

    name: str
    config: str
    experiments: tuple[str, ...]
    expected_min: float
    planners: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.name or "/" in self.name:
            raise ConfigError(f"canonical run name {self.name!r}: give a folder name, no '/'")
        if self.expected_min <= 0:
            raise ConfigError(f"canonical run {self.name}: expected_min must be positive")


@dataclass(frozen=True)
class CanonicalSweeps:
    """The built-in sweeps named by ``parameters`` (``configs/sweeps/``) into ``<out>/<name>``."""

    name: str
    parameters: tuple[str, ...]
    expected_min: float


@dataclass(frozen=True)
class Canonical:
    runs: tuple[CanonicalRun, ...]
    sweeps: CanonicalSweeps | None = None

    def __post_init__(self) -> None:
        names = [r.name for r in self.runs] + ([self.sweeps.name] if self.sweeps else [])
        if len(set(names)) != len(names):
            raise ConfigError(f"canonical runs: folder names repeat: {names}")

    def names(self) -> list[str]:
        return [r.name for r in self.runs] + ([self.sweeps.name] if self.sweeps else [])

    def expected_min(self, only: set[str] | None = None) -> float:
        parts = [*self.runs, *([self.sweeps] if self.sweeps else [])]
        return sum(p.expected_min for p in parts if only is None or p.name in only)


def load_canonical(name_or_path: str | Path = CANONICAL) -> Canonical:
    return from_dict(Canonical, load_config_data(name_or_path), where=str(name_or_path))


def missing_planners(canon: Canonical, protocol: str | None = None) -> dict[str, str]:
    """``{planner: why it cannot run here}`` over every canonical run (empty: all can run)."""
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.planner.registry import unavailable

    missing = {}
    for run in canon.runs:
        for planner in load_experiment_config(protocol or run.config).planners:
            why = unavailable(planner)
            if why is not None:
                missing[planner] = why
    return missing


def pack_attempts(run_dir: Path) -> list[Path]:
    """Replace ``run_dir/attempts.csv`` by ``attempts.csv.gz`` (byte-reproducible; in pieces
    ``attempts.csv.gz.00``, ... where it would pass 2 MiB); returns the files written."""
    from hsqbench.experiment.rows import attempts_paths, write_packed

    plain, packed = attempts_paths(run_dir)
    written = write_packed(packed, plain.read_bytes())  # whole before the plain file goes
    plain.unlink()
    return written


def unpack_attempts(run_dir: Path) -> None:
    """Undo :func:`pack_attempts` so that the run can be resumed (a no-op on a plain run)."""
    from hsqbench.experiment.rows import attempts_paths, packed_files, read_packed

    plain, packed = attempts_paths(run_dir)
    files = packed_files(packed)
    if not files:
        return
    if plain.exists():
        raise FileExistsError(
            f"{run_dir} holds both {plain.name} and {files[0].name}: keep the one with the "
            "run's rows (the larger) and delete the other"
        )
    tmp = plain.with_name(plain.name + ".tmp")
    tmp.write_bytes(read_packed(packed))
    tmp.replace(plain)
    for f in files:
        f.unlink()


def make_results(
    canon: Canonical,
    out: Path,
    *,
    only: set[str] | None = None,
    protocol: str | None = None,
    jobs: int | None = None,
    backend_factory=None,
    progress: bool = True,
) -> int:
    """Run (or resume) the selected canonical runs into ``out``; return the trials that failed
    with an infrastructure error. ``protocol`` replaces every run's protocol config (``quick``:
    the logic in minutes, not the canonical numbers); ``backend_factory(config)`` replaces the
    simulator (tests)."""
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.experiment.executor import make_executor
    from hsqbench.experiment.report import write_report
    from hsqbench.experiment.runner import run_benchmark
    from hsqbench.runs import protocol_planners

    executor = make_executor("local", jobs)
    errors = 0
    for run in canon.runs:
        if only is not None and run.name not in only:
            continue
        config_name = protocol or run.config
        config, planners = protocol_planners(
            load_experiment_config(config_name), list(run.planners) or None
        )
        experiments = [e for e in run.experiments if e in config.enabled_experiments()]
        if not experiments:  # only with --protocol: the canonical list is checked by its test
            print(f"== {run.name}: {config_name} has none of {', '.join(run.experiments)}")
            continue
        print(f"== {out / run.name}: {config_name}, about {run.expected_min:.0f} min", flush=True)
        unpack_attempts(out / run.name)
        summary = run_benchmark(
            config,
            out / run.name,
            backend=backend_factory(config) if backend_factory else None,
            executor=executor,
            planners=planners,
            experiments=experiments,
            resume=True,
            retry_errors=True,
            progress=progress,
            config_name=config_name,
        )
        write_report(out / run.name)
        if summary.errors == 0:
            pack_attempts(out / run.name)
        errors += summary.errors
    if canon.sweeps is not None and (only is None or canon.sweeps.name in only):
        from hsqbench.cli import main as cli_main

        argv = ["sweep", *canon.sweeps.parameters, "--run", str(out / canon.sweeps.name)]
        argv += ["--resume", "--retry-errors", *(["--protocols", protocol] if protocol else [])]
        print(f"== {out / canon.sweeps.name}: about {canon.sweeps.expected_min:.0f} min")
        errors += cli_main([*argv, *(["--jobs", str(jobs)] if jobs else [])]) != 0
    return errors


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="make results",
        description="(Re)make the canonical runs behind the README's tables and plots "
        "(configs/canonical.yaml), resuming what is there.",
    )
    parser.add_argument("--list", default=CANONICAL, help="the canonical list (configs/ name)")
    parser.add_argument("--out", type=Path, default=REPO_ROOT / "results", help="where runs go")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="only these runs of the list")
    parser.add_argument("--protocol", help="run every entry on this protocol instead (quick)")
    parser.add_argument("--jobs", type=int, default=None, help="worker processes")
    parser.add_argument("--dry-run", action="store_true", help="list the runs and their time")
    args = parser.parse_args(argv)
    canon = load_canonical(args.list)
    only = set(args.only) if args.only else None
    if only is not None and only - set(canon.names()):
        unknown = sorted(only - set(canon.names()))
        parser.error(f"--only {' '.join(unknown)}: not in the list ({', '.join(canon.names())})")
    hours = canon.expected_min(only) / 60
    print(f"canonical runs into {args.out}: {', '.join(sorted(only or canon.names()))}")
    print(f"expected: about {hours:.1f} h with --jobs 2 on a 2-core machine (resumable)")
    if args.dry_run:
        return 0
    missing = missing_planners(canon, args.protocol)
    if missing:
        why = "; ".join(f"{name}: {reason}" for name, reason in sorted(missing.items()))
        print(f"cannot make the canonical runs without every planner ({why})", file=sys.stderr)
        return 2
    errors = make_results(canon, args.out, only=only, protocol=args.protocol, jobs=args.jobs)
    if errors:
        print(f"{errors} trial(s) failed; rerun `make results` to retry them", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
