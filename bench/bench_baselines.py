"""Time the baseline planners (``single-sq``, ``antipodal``) on 10k-point clouds, one core.

Clouds: a box, an L of two boxes, the mug-like and the box-on-cylinder shapes of tests/shapes.py,
and, when HSQ_YCB_DIR is set, the YCB mug and cracker box; each seen by two side cameras with
1 mm noise and resampled to exactly ``--points`` points. BLAS and OpenMP run on one thread. The
hsq planner is timed on the same clouds for reference (``--no-hsq`` leaves it out).

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

from hsqbench.planner.api import PlanningContext  # noqa: E402
from hsqbench.planner.registry import get_planner  # noqa: E402
from hsqbench.settings import ycb_dir  # noqa: E402
from tests.shapes import (  # noqa: E402
    Box,
    cylinder_with_box_on_top,
    l_of_two_boxes,
    mug_with_handle,
    union_cloud,
    visible_mask,
)

CENTRE = np.array([0.5, 0.0, 0.0])
CAMERAS = np.array([[0.62, 0.78, 0.55], [0.62, -0.78, 0.55]])
TABLE = (0.0, 0.0, 1.0, 0.0)


def seen(points: np.ndarray, normals: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    mask = np.zeros(len(points), dtype=bool)
    for camera in CAMERAS:
        mask |= visible_mask(points, normals, camera)
    points = points[mask]
    points = points[rng.choice(len(points), size=n, replace=len(points) < n)]
    return points + rng.normal(scale=0.001, size=points.shape)


def clouds(n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    out = {}
    box = Box((0.03, 0.02, 0.05), center=CENTRE + np.array([0.0, 0.0, 0.05]))
    for name, parts in (
        ("box 6x4x10", (box,)),
        ("L of two boxes", l_of_two_boxes(translation=CENTRE)),
        ("mug-like", mug_with_handle(translation=CENTRE)),
        ("box-on-cylinder", cylinder_with_box_on_top(translation=CENTRE)),
    ):
        cloud = union_cloud(parts, 0.0008, rng)
        out[name] = seen(cloud.points, cloud.normals, n, rng)
    root = ycb_dir(required=False)
    if root is not None:
        import trimesh

        for name in ("mug", "cracker_box"):
            mesh = trimesh.load(root / name / "textured.obj", force="mesh", process=False)
            verts = mesh.vertices - [*mesh.vertices[:, :2].mean(axis=0), mesh.vertices[:, 2].min()]
            mesh = trimesh.Trimesh(verts + CENTRE, mesh.faces, process=False)
            points, faces = trimesh.sample.sample_surface(mesh, 6 * n, seed=0)
            out[f"ycb {name}"] = seen(points, mesh.face_normals[faces], n, rng)
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
    context = PlanningContext(support_plane=TABLE, seed=0)
    print(
        f"{'cloud':16s} {'planner':9s} {'total':>6s} {'p90':>6s}  stages (median s)"
        f"{'':38s} {'lines':>6s} {'grasps':>6s} {'best':>5s}"
    )
    for cloud_name, cloud in clouds(args.points, rng).items():
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
