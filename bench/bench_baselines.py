"""Time the baseline planners (``single-sq``, ``antipodal``) on 10k-point clouds, one core.

Clouds: a box and an L of two boxes of tests/shapes.py, seen by two side cameras with 1 mm
noise, plus the clouds of bench_planner.py (two synthetic shapes, and with HSQ_YCB_DIR the
harness's own clouds of the YCB cracker box and three packed scenes), each with exactly
``--points`` points and planned with its table plane and camera centres. BLAS and OpenMP run on
one thread. The hsq planner is timed on the same clouds for reference (``--no-hsq`` leaves it
out).

    .venv/bin/python bench/bench_baselines.py [--points 10000] [--repeats 5] [--no-hsq]
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

from bench_planner import CAMERAS, CENTRE, TABLE, seen  # noqa: E402
from bench_planner import clouds as planner_clouds  # noqa: E402

from hsqbench.planner.api import PlanningContext  # noqa: E402
from hsqbench.planner.registry import get_planner  # noqa: E402
from tests.shapes import Box, l_of_two_boxes, union_cloud  # noqa: E402


def clouds(n: int, rng: np.random.Generator) -> dict[str, tuple[np.ndarray, dict]]:
    """bench_planner's clouds (synthetic, the YCB cracker box, packed scenes) plus a box and an
    L of two boxes: name -> (cloud, PlanningContext keyword arguments)."""
    out = {}
    box = Box((0.03, 0.02, 0.05), center=CENTRE + np.array([0.0, 0.0, 0.05]))
    for name, parts in (
        ("box 6x4x10", (box,)),
        ("L of two boxes", l_of_two_boxes(translation=CENTRE)),
    ):
        cloud = union_cloud(parts, 0.0008, rng)
        kwargs = {"support_plane": TABLE, "camera_positions": CAMERAS}
        out[name] = (seen(cloud.points, cloud.normals, n, rng), kwargs)
    out.update(planner_clouds(n, rng))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-hsq", action="store_true", help="leave the hsq reference out")
    args = parser.parse_args()
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
    rng = np.random.default_rng(0)
    names = ["single-sq", "antipodal"] + ([] if args.no_hsq else ["hsq"])
    planners = {name: get_planner(name) for name in names}
    print(
        f"{'cloud':16s} {'planner':9s} {'total':>6s} {'p90':>6s}  stages (median s)"
        f"{'':38s} {'lines':>6s} {'grasps':>6s} {'best':>5s}"
    )
    for cloud_name, (cloud, kwargs) in clouds(args.points, rng).items():
        context = PlanningContext(seed=0, **kwargs)
        for name, planner in planners.items():
            planner.plan(cloud, context)  # warm-up: imports, caches
            totals, stages = [], {}
            for _ in range(args.repeats):
                start = time.perf_counter()
                result = planner.plan(cloud, context)
                totals.append(time.perf_counter() - start)
                for key, value in result.timings.items():
                    if key != "total":
                        stages.setdefault(key, []).append(value)
            stage_text = " ".join(f"{k} {np.median(v):.3f}" for k, v in stages.items())
            lines = len(result.candidates.lines) if result.candidates is not None else 0
            best = f"{result.best.score:.2f}" if result.best else "-"
            print(
                f"{cloud_name:16s} {name:9s} {np.median(totals):6.3f} "
                f"{np.quantile(totals, 0.9):6.3f}  {stage_text:54s} {lines:6d} "
                f"{len(result.grasps):6d} {best:>5s}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
