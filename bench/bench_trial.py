"""Where a trial's time goes, and how two code versions compare on the same trials.

Trials are *presentations* as a benchmark runs them: an isolated pose of one object (the
protocol's own seed for that object and pose index) or a packed round (the protocol's draw),
each run for every ``--planners`` through the executor and backend of ``hsqbench benchmark``
(``SerialExecutor``, ``SimBackend``) with its rows written by a ``ResultStore``. The first
trial of a process pays for imports and the GL context and is not timed (a warm-up trial runs
first).

Default: each presentation's wall and CPU seconds per trial, and the exclusive seconds per
step of a trial (scene build: compile, settle; perception: renderer set-up, render,
back-projection; graspability; planning; motion planning: IK, checks; execution: physics and
the Python around it; results rows; ``trial_timing.py``), in this process.

``--compare REF``: the same presentations on commit ``REF`` (exported with ``git archive``
under the temp folder) and on this working tree, in two worker processes, interleaved
(``trial_compare.py``); prints the ratios new/ref of wall and CPU seconds per trial and whether
every attempt's outcome is identical.

``--jobs-compare``: the presentations run by ``--jobs 1`` and ``--jobs 2`` (the local
executor's process pool) in turn: wall seconds per trial of each.

``--set KEY=VALUE`` (repeatable) changes a trial-config value for this working tree's runs, as
a sweep point does (``physics.timestep_s=0.004``, ``ik.restarts=4``): with ``--compare REF`` the
reference keeps its own config, so the ratios price a candidate setting against ``REF``, and
the outcome check shows which attempts it changed.

Run with ``nice`` on a shared machine and report its load (``uptime``); the paper's objects
and the unseen ones use their protocols' trial configs (``trial`` / ``trial_resting``).

    .venv/bin/python bench/bench_trial.py [--paper 3] [--unseen 3] [--packed 0]
        [--poses 1] [--first-pose 0] [--planners hsq antipodal] [--set KEY=VALUE ...]
        [--compare REF | --jobs-compare]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

HERE = Path(__file__).resolve()
sys.path.insert(0, str(HERE.parent))

#: Presentation used to warm a process up (imports, GL context, IK library), never timed.
WARMUP = ("foam_brick", 999)


def _spread(names: tuple[str, ...], n: int) -> list[str]:
    """``n`` names spread evenly over the list (its order is the config's)."""
    if n >= len(names):
        return list(names)
    return [names[int(i)] for i in np.linspace(0, len(names) - 1, n).round()]


def build_groups(args: argparse.Namespace) -> list[dict]:
    """The presentations, as worker requests: name, kind, trial config and specs."""
    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.experiment.seeds import derive_seed, draw_packed_round

    groups = []
    for kind, config_name, n in (("paper", "paper", args.paper), ("unseen", "ycb", args.unseen)):
        if n <= 0:
            continue
        cfg = load_experiment_config(config_name)
        for obj in _spread(cfg.isolated.objects, n):
            for index in range(args.first_pose, args.first_pose + args.poses):
                seed = derive_seed(0, "isolated", obj, index)
                specs = [["isolated", p, 0, index, [obj], seed] for p in args.planners]
                groups.append(_group(f"{obj}/{index}", f"{kind} isolated", cfg, specs))
    if args.packed > 0:
        from hsqbench.experiment.backend import SimBackend

        cfg = load_experiment_config("paper")
        pk, backend = cfg.packed, SimBackend(cfg.trial_config)
        for i in range(args.packed):
            draw = draw_packed_round(
                pk.objects, pk.objects_per_round, 0, i, backend.placeable, pk.max_draws
            )
            seed = derive_seed(0, "packed", "round", i)
            specs = [["packed", p, 0, i, list(draw.objects), seed] for p in args.planners]
            groups.append(_group(f"packed round {i}", "paper packed", cfg, specs))
    return groups


def _group(name: str, kind: str, cfg, specs: list) -> dict:
    return {"name": name, "kind": kind, "trial_config": cfg.trial_config, "specs": specs}


def parse_overrides(items: list[str]) -> dict[str, object]:
    """``--set`` items as trial-config overrides, checked against the trial config here, so a
    typo fails before any worker starts."""
    from hsqbench.config import load_tree
    from hsqbench.errors import ConfigError
    from hsqbench.overrides import parse_assignments
    from hsqbench.sim.trial import TrialConfig

    try:
        out = parse_assignments(items)
    except ConfigError as err:
        raise SystemExit(str(err)) from None
    try:
        if out:
            load_tree(TrialConfig, "trial", out)
    except (TypeError, ValueError) as err:  # ConfigError is a ValueError
        raise SystemExit(f"--set: {err}") from None
    return out


def warmup_group(planner: str) -> dict:
    from hsqbench.experiment.seeds import derive_seed

    obj, index = WARMUP
    spec = ["isolated", planner, 0, index, [obj], derive_seed(0, "isolated", obj, index)]
    return {"name": "warm-up", "kind": "warm-up", "trial_config": "trial", "specs": [spec]}


class Runner:
    """Runs worker requests with this process's hsqbench: executor, backend and result rows."""

    def __init__(self, jobs: int = 1) -> None:
        from hsqbench.experiment.executor import make_executor

        self.executor = make_executor("local", jobs)
        self.backends: dict[tuple, object] = {}
        self.rows = tempfile.mkdtemp(prefix="bench-trial-rows-")
        self.runs = 0

    def run(self, request: dict) -> dict:
        from hsqbench.experiment.backend import SimBackend
        from hsqbench.experiment.seeds import TrialSpec

        overrides = tuple(sorted(request.get("overrides", {}).items()))
        key = (request["trial_config"], overrides)
        if key not in self.backends:  # a reference version may predate overrides: none given
            extra = {"overrides": overrides} if overrides else {}
            self.backends[key] = SimBackend(request["trial_config"], **extra)
        backend = self.backends[key]
        specs = [TrialSpec(e, p, b, i, tuple(o), s) for e, p, b, i, o, s in request["specs"]]
        # As a benchmark does before its trials: build (or load) the objects; not timed.
        backend.prepare(tuple(dict.fromkeys(o for s in specs for o in s.objects)), 1, False)
        from hsqbench.experiment.results import ResultStore

        store = ResultStore(Path(self.rows) / f"request{self.runs}")
        store.prepare()
        trials = []
        w0, c0 = time.perf_counter(), time.process_time()
        for run in self.executor.run(backend, specs):
            store.append(run, "bench", "bench")
            trials.append(_trial_record(run))
        self.runs += 1
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        return {"trials": trials, "wall_s": wall, "cpu_s": cpu}


def _trial_record(run) -> dict:
    from trial_compare import OUTCOME_FIELDS

    result = run.result
    attempts = [] if result is None else result.attempts
    outcomes = [[repr(getattr(a, f, None)) for f in OUTCOME_FIELDS] for a in attempts]
    for f in ("objects_cleared", "objects_lost", "objects_graspable"):
        if hasattr(result, f):
            outcomes.append([f, repr(getattr(result, f))])
    summary = " ".join(a.outcome.value for a in attempts) or f"error: {run.error}"
    return {
        "key": run.spec.key,
        "wall_s": run.wall_s,
        "error": run.error,
        "outcomes": outcomes,
        "summary": summary,
    }


def worker() -> int:
    """Answer one JSON request per stdin line with one JSON line (everything else the trial
    code prints goes to stderr)."""
    out = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    runner = Runner()
    for line in sys.stdin:
        out.write(json.dumps(runner.run(json.loads(line))) + "\n")
        out.flush()
    return 0


def breakdown(groups: list[dict], planners: list[str]) -> None:
    from trial_timing import Attribution

    runner = Runner()
    runner.run(warmup_group(planners[0]))
    timing = Attribution()
    missing = timing.install()
    if missing:
        print(f"(not wrapped, absent in this version: {', '.join(missing)})")
    timing.reset()
    trials = 0
    print(f"{'presentation':34s} {'trials':>6s} {'wall_s':>7s} {'cpu_s':>7s}  outcomes")
    for g in groups:
        reply = runner.run(g)
        n = len(g["specs"])
        trials += n
        print(
            f"{g['name']:34s} {n:6d} {reply['wall_s'] / n:7.2f} {reply['cpu_s'] / n:7.2f}  "
            + ", ".join(t["summary"] for t in reply["trials"]),
            flush=True,
        )
    timing.uninstall()
    print(f"\nwhere the time goes, seconds per trial ({trials} trials):")
    print("\n".join(timing.table(trials)))


def jobs_compare(groups: list[dict], planners: list[str], rounds: int = 2) -> None:
    """Wall seconds per trial of all presentations run with --jobs 1 and --jobs 2 in turn."""
    runners = {1: Runner(1), 2: Runner(2)}
    runners[1].run(warmup_group(planners[0]))
    # One executor call per trial config, as a benchmark makes one for all its trials.
    batches: dict[str, dict] = {}
    for g in groups:
        batch = batches.setdefault(g["trial_config"], {**g, "specs": []})
        batch["specs"] = batch["specs"] + g["specs"]
    walls: dict[int, list[float]] = {1: [], 2: []}
    n = sum(len(g["specs"]) for g in groups)
    for r in range(rounds):
        for jobs in (1, 2) if r % 2 == 0 else (2, 1):
            t0 = time.perf_counter()
            for batch in batches.values():
                runners[jobs].run(batch)
            walls[jobs].append((time.perf_counter() - t0) / n)
            print(f"--jobs {jobs}: {walls[jobs][-1]:.2f} s wall per trial", flush=True)
    j1, j2 = np.median(walls[1]), np.median(walls[2])
    print(f"median: --jobs 1 {j1:.2f} s, --jobs 2 {j2:.2f} s per trial (speed-up {j1 / j2:.2f})")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--paper", type=int, default=3, help="objects of the paper's 15")
    parser.add_argument("--unseen", type=int, default=3, help="objects of the unseen protocol")
    parser.add_argument("--packed", type=int, default=0, help="packed rounds (paper protocol)")
    parser.add_argument("--poses", type=int, default=1, help="pose indices per object")
    parser.add_argument("--first-pose", type=int, default=0, help="the first pose index")
    parser.add_argument("--planners", nargs="+", default=["hsq", "antipodal"])
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--compare", metavar="REF", help="also run commit REF and print ratios")
    mode.add_argument("--jobs-compare", action="store_true", help="--jobs 1 against --jobs 2")
    mode.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a trial-config value for this tree's runs (not REF's), e.g. physics.timestep_s=0.004",
    )
    args = parser.parse_args()
    if args.worker:
        return worker()
    overrides = parse_overrides(args.set)
    if overrides and args.jobs_compare:
        parser.error(
            "--set prices a setting against --compare REF or in the breakdown, "
            "not in --jobs-compare"
        )
    groups = [{**g, "overrides": overrides} if overrides else g for g in build_groups(args)]
    if not groups:
        parser.error("nothing to run: give --paper, --unseen or --packed a positive count")
    if args.jobs_compare:
        jobs_compare(groups, args.planners)
    elif args.compare:
        from trial_compare import compare, export_version, summarise

        repo = HERE.parents[1]
        ref_root, commit = export_version(repo, args.compare)
        print(f"reference {args.compare} = {commit[:12]} in {ref_root}; new: {repo}")
        results = compare(groups, warmup_group(args.planners[0]), ref_root, repo, HERE)
        print("\n".join(summarise(results)))
    else:
        breakdown(groups, args.planners)
    print(
        f"load: {os.getloadavg()[0]:.1f} {os.getloadavg()[1]:.1f} (1, 5 min), {os.cpu_count()} cores"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
