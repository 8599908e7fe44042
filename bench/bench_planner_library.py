"""CPU time of the hsq planner per isolated attempt on one core, over the whole YCB library.

The clouds are those of the benchmark's isolated attempts: each object of HSQ_YCB_DIR in its
resting poses (``configs/scene_resting.yaml``) seen by the two depth cameras with the configured
sensor model, rendered once and cached by ``bench/harness_clouds.py``. Each is planned
``--repeats`` times through the registered planner (as the trial runner calls it: table plane,
camera centres, seed) with BLAS, OpenMP and K-means on one thread and malloc keeping freed memory
as a benchmark's trial process does (:mod:`hsqbench.experiment.heap`); the CPU time of a cloud is
the median of its repeats. Printed: the median and 90th percentile over the paper's 15 and over
the other objects, the slowest clouds and the median stage times. Target of tracker issue 42: a
median of at most 0.1 s per isolated attempt on one core (issue 13's was 0.2 s).

``--save PATH`` writes every cloud's grasps (poses, widths, scores) to an ``.npz``;
``--compare PATH`` checks them against such a file, so that a change meant to make the planner
faster and nothing else is shown to leave every grasp as it was.

    .venv/bin/python bench/bench_planner_library.py [--seeds 0 1 2] [--repeats 3] [--objects all]
    .venv/bin/python bench/bench_planner_library.py --save /tmp/before.npz
    .venv/bin/python bench/bench_planner_library.py --compare /tmp/before.npz
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from harness_clouds import object_names, observe  # noqa: E402

from hsqbench.experiment.machine import cpu_model  # noqa: E402
from hsqbench.planner.api import PlanningContext  # noqa: E402
from hsqbench.planner.registry import get_planner  # noqa: E402
from hsqbench.settings import code_version  # noqa: E402

#: The scene config of the unseen-object protocol's isolated attempts (resting poses).
SCENE = "scene_resting"
#: Target of issue 42, seconds of CPU per isolated attempt (median; issue 13's was 0.2).
TARGET_S = 0.1


def grasp_array(result) -> np.ndarray:
    """(n, 14): each grasp's position, rotation (row-major), width and score."""
    rows = [
        np.concatenate([g.position, g.rotation.ravel(), [g.width, g.score]]) for g in result.grasps
    ]
    return np.array(rows, dtype=float).reshape(-1, 14)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", nargs="*", default=["all"], help="names, paper, unseen, all")
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--planner", default="hsq", help="a registered planner")
    parser.add_argument("--planner-config", default=None, help="planner config name or path")
    parser.add_argument("--save", default=None, help="write every cloud's grasps to this .npz")
    parser.add_argument("--compare", default=None, help="check the grasps against this .npz")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    from threadpoolctl import threadpool_limits

    from hsqbench.experiment.config import YCB_OBJECTS
    from hsqbench.experiment.heap import keep_freed_memory

    threadpool_limits(1)
    keep_freed_memory()  # as in a benchmark's trial process
    paper = set(YCB_OBJECTS)
    reference = dict(np.load(args.compare)) if args.compare else None
    planner = get_planner(args.planner, args.planner_config)
    cpu: dict[str, float] = {}
    stages: dict[str, list[float]] = {}
    grasps: dict[str, np.ndarray] = {}
    for name in object_names(args.objects):
        for seed in args.seeds:
            obs = observe(name, seed, None, refresh=False, scene=SCENE)
            context = PlanningContext(
                support_plane=tuple(obs["support_plane"]),
                seed=seed,
                camera_positions=obs["camera_positions"],
            )
            if not cpu:  # warm-up: imports and caches stay out of the first time
                planner.plan(obs["points"], context)
            times = []
            for _ in range(args.repeats):
                start = time.process_time()
                result = planner.plan(obs["points"], context)
                times.append(time.process_time() - start)
            key = f"{name}/s{seed}"
            cpu[key] = float(np.median(times))
            for stage, seconds in result.timings.items():
                stages.setdefault(stage, []).append(seconds)
            grasps[key] = grasp_array(result)
            print(f"{key:28s} {len(obs['points']):6d} pts {cpu[key]:6.3f} s", flush=True)
    report(cpu, stages, paper)
    if args.save:
        np.savez_compressed(args.save, **grasps)
        print(f"grasps of {len(grasps)} clouds written to {args.save}")
    if reference is not None:
        return compare(grasps, reference)
    return 0


def report(cpu: dict[str, float], stages: dict[str, list[float]], paper: set[str]) -> None:
    """Medians per group, the slowest clouds and the median stage times."""
    groups = {
        "paper's 15": [t for k, t in cpu.items() if k.split("/")[0] in paper],
        "others": [t for k, t in cpu.items() if k.split("/")[0] not in paper],
        "all": list(cpu.values()),
    }
    for group, values in groups.items():
        if values:
            print(
                f"{group:10s} {len(values):4d} clouds: median {np.median(values):.3f} s CPU, "
                f"90th percentile {np.percentile(values, 90):.3f} s, max {max(values):.3f} s"
            )
    slowest = sorted(cpu, key=cpu.get, reverse=True)[:5]
    print("slowest: " + ", ".join(f"{k} {cpu[k]:.2f} s" for k in slowest))
    print("median stage wall s: " + ", ".join(f"{s} {np.median(v):.3f}" for s, v in stages.items()))
    print(f"target of issue 42: median <= {TARGET_S} s per isolated attempt on one core")
    # The same code measured 0.16-0.185 s (unseen median) on one 2-core machine and 0.23 s on
    # another: a figure means little without the CPU it ran on.
    print(f"machine: {cpu_model()}, {os.cpu_count()} CPUs, code {code_version()}")


def compare(grasps: dict[str, np.ndarray], reference: dict[str, np.ndarray]) -> int:
    """0 when every cloud's grasps match the reference (poses to 1e-9 m, same order)."""
    changed = [
        key
        for key, mine in grasps.items()
        if key not in reference
        or reference[key].shape != mine.shape
        or not np.allclose(reference[key], mine, rtol=0.0, atol=1e-9)
    ]
    if changed:
        print(
            f"grasps differ from the reference on {len(changed)} of {len(grasps)} clouds: "
            + ", ".join(changed[:10])
        )
        return 1
    print(f"grasps identical to the reference on all {len(grasps)} clouds")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
