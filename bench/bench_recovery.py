"""Time stage one (hidden superquadric recovery) on fused two-camera clouds of YCB-sized objects.

Each YCB mesh ($HSQ_YCB_DIR/<name>/textured.obj, z up) is sampled at 1 mm, and the points two
depth cameras see are kept: the cameras stand 1 m away on both sides of the table (azimuth +-90
deg, 40 deg elevation), with a z-buffer of 2.2 mm pixels (an Azure Kinect NFOV pixel at 1 m).
Points within 5 mm of the table are cropped, 1.5 mm Gaussian noise is added (ToF noise at 1 m) and
the fused cloud is voxelised at 2 mm, as the harness's perception does. Without HSQ_YCB_DIR the
procedural unions of tests/shapes.py are used instead.

Everything runs on one core (BLAS and OpenMP pools limited to one thread). Per object: cloud size,
the paper's K, the number of hidden superquadrics found, wall and CPU time of
``recover_hidden_superquadrics`` and the CPU time spent in its alpha/beta calls (medians over
repeats). The target is a median under 0.2 s for the fits: everything but alpha/beta
(downsampling, K-means, all EMS runs).

    .venv/bin/python bench/bench_recovery.py [--repeats N] [--objects a,b,...]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hsqbench.planner.downsample import voxel_downsample  # noqa: E402
from hsqbench.planner.hsq.config import load_planner_config  # noqa: E402
from hsqbench.planner.hsq.stage_one import recovery  # noqa: E402
from hsqbench.settings import ycb_dir  # noqa: E402
from tests.shapes import (  # noqa: E402
    cylinder_with_box_on_top,
    l_of_two_boxes,
    mug_with_handle,
    union_cloud,
    visible_mask,
)

SAMPLE_SPACING_M = 0.001
CAMERA_DISTANCE_M = 1.0
CAMERA_ELEVATION_DEG = 40.0
PIXEL_M = 0.0022
TABLE_CROP_M = 0.005
NOISE_M = 0.0015
VOXEL_M = 0.002


def _cameras(centre: np.ndarray) -> list[np.ndarray]:
    el = np.radians(CAMERA_ELEVATION_DEG)
    return [
        centre + CAMERA_DISTANCE_M * np.array([0.0, side * np.cos(el), np.sin(el)])
        for side in (1.0, -1.0)
    ]


def fused_cloud(points: np.ndarray, normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """What two side cameras see of a surface sampling (z up, table at z = 0), fused."""
    centre = points.mean(axis=0)
    seen = np.zeros(len(points), dtype=bool)
    for cam in _cameras(centre):
        seen |= visible_mask(points, normals, cam, pixel_m=PIXEL_M)
    cloud = points[seen & (points[:, 2] > TABLE_CROP_M)]
    cloud = cloud + rng.normal(scale=NOISE_M, size=cloud.shape)
    return voxel_downsample(cloud, VOXEL_M).points


def ycb_clouds(names: list[str] | None, rng: np.random.Generator) -> dict[str, np.ndarray]:
    import trimesh

    root = ycb_dir(required=False)
    if root is None:
        return {}
    found = sorted(p.parent.name for p in root.glob("*/textured.obj"))
    out = {}
    for name in names or found:
        mesh = trimesh.load(root / name / "textured.obj", force="mesh")
        mesh.apply_translation([-mesh.centroid[0], -mesh.centroid[1], -mesh.bounds[0, 2]])
        count = int(mesh.area / SAMPLE_SPACING_M**2)
        pts, faces = trimesh.sample.sample_surface(mesh, count, seed=int(rng.integers(1 << 31)))
        out[name] = fused_cloud(np.asarray(pts), mesh.face_normals[faces], rng)
    return out


def procedural_clouds(rng: np.random.Generator) -> dict[str, np.ndarray]:
    out = {}
    for make in (l_of_two_boxes, cylinder_with_box_on_top, mug_with_handle):
        pc = union_cloud(make(), SAMPLE_SPACING_M, rng)
        out[make.__name__] = fused_cloud(pc.points, pc.normals, rng)
    return out


class _Timed:
    """Wraps recovery's alpha/beta to add up the CPU time spent in it."""

    def __init__(self, func):
        self.func, self.seconds = func, 0.0

    def __call__(self, *args):
        c0 = time.process_time()
        try:
            return self.func(*args)
        finally:
            self.seconds += time.process_time() - c0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--objects", type=str, default="", help="comma-separated YCB names")
    args = parser.parse_args()
    cfg = load_planner_config().recovery
    rng = np.random.default_rng(0)
    clouds = ycb_clouds([n for n in args.objects.split(",") if n] or None, rng)
    source = "YCB"
    if not clouds:
        clouds, source = procedural_clouds(rng), "procedural (HSQ_YCB_DIR not set)"
    timed = _Timed(recovery.alpha_beta)
    recovery.alpha_beta = timed
    print(f"stage one on one core, {source} clouds, medians over {args.repeats} runs (CPU s)")
    print(
        f"{'object':22s} {'points':>6s} {'K':>3s} {'found':>5s} {'wall':>6s} {'cpu':>6s} "
        f"{'a/b':>6s} {'fits':>6s}"
    )
    rows = []
    with threadpool_limits(limits=1):
        for name, cloud in clouds.items():
            walls, cpus, abs_ = [], [], []
            for _ in range(args.repeats):
                timed.seconds = 0.0
                w0, c0 = time.perf_counter(), time.process_time()
                hidden = recovery.recover_hidden_superquadrics(cloud, cfg, seed=0)
                walls.append(time.perf_counter() - w0)
                cpus.append(time.process_time() - c0)
                abs_.append(timed.seconds)
            cpu, ab = float(np.median(cpus)), float(np.median(abs_))
            fits = float(np.median(np.array(cpus) - np.array(abs_)))
            rows.append((cpu, fits))
            print(
                f"{name:22s} {len(cloud):6d} {recovery.part_count(cloud, cfg):3d} "
                f"{len(hidden):5d} {np.median(walls):6.3f} {cpu:6.3f} {ab:6.3f} {fits:6.3f}"
            )
    arr = np.array(rows)
    print(
        f"median over objects: stage one {np.median(arr[:, 0]):.3f} s, of which the fits "
        f"(everything but alpha/beta) {np.median(arr[:, 1]):.3f} s; target < 0.2 s for the fits"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
