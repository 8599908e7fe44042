"""Trial throughput: isolated trials per second in one process (``--jobs 1``), and what making
the depth sensor costs per trial.

A fixed set (objects x seeds, the paper's planner) runs after one warm-up trial (imports, the IK
seed library, the first GL context), so the number is the steady rate a worker reaches; a sweep
multiplies exactly this. One thread (BLAS and OpenMP pinned before numpy loads). Assets must be
built (the first benchmark builds them; the asset cache is shared).

    .venv/bin/python bench/bench_trials.py [--objects tomato_soup_can foam_brick] [--seeds 3]
        [--planner hsq]
"""

from __future__ import annotations

import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

OBJECTS = ["tomato_soup_can", "foam_brick", "mustard_bottle", "sugar_box"]


def sensor_cost(obj: str, repeats: int) -> float:
    """Median seconds to make (and close) the trial's depth sensor for one built scene."""
    from hsqbench.sim.perception import Perception
    from hsqbench.sim.scene import build_scene

    model, _, info = build_scene("isolated", obj, seed=0)
    times = []
    for i in range(repeats + 1):
        t0 = time.perf_counter()
        with Perception.from_scene(model, info, rng=np.random.default_rng(i)):
            pass
        if i:  # the first pays for the process's GL context
            times.append(time.perf_counter() - t0)
    return float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", nargs="+", default=OBJECTS)
    parser.add_argument("--seeds", type=int, default=3, help="seeds per object (default 3)")
    parser.add_argument("--planner", default="hsq")
    args = parser.parse_args()

    from hsqbench.sim.trial import load_trial_config, run_isolated_trial

    config = load_trial_config()
    run_isolated_trial(args.objects[0], 10_000, args.planner, config)  # warm-up, not counted
    walls, outcomes = [], []
    t_all = time.perf_counter()
    for obj in args.objects:
        for seed in range(args.seeds):
            t0 = time.perf_counter()
            result = run_isolated_trial(obj, seed, args.planner, config)
            walls.append(time.perf_counter() - t0)
            outcomes.append(result.attempts[0].outcome.value)
    total = time.perf_counter() - t_all
    n = len(walls)
    print(f"{n} isolated trials ({args.planner}; {len(args.objects)} objects x {args.seeds} seeds)")
    print(
        f"  throughput: {n / total:.3f} trials/s ({total:.1f} s; median {np.median(walls):.2f} s)"
    )
    print(f"  outcomes: {sorted(outcomes)}")
    print(f"  making the depth sensor: {1000 * sensor_cost(args.objects[0], 5):.0f} ms per trial")


if __name__ == "__main__":
    main()
