"""Cloud cleaning (``hsqbench.planner.cleaning``) on the benchmark's clouds: what it removes, and
its cost.

For the 15 YCB objects x seeds, the isolated-scene clouds of ``bench/harness_clouds.py`` (same
cache) with the ToF noise alone (``--sensor tof``: the calibration error shifts whole views by a
few millimetres, which no local filter can tell from the surface) are compared with the object's
true mesh. For each radius and neighbour count: the share of *far* points (more than 1 cm from
the mesh: flying pixels) that stay, and the share of *surface* points (within 4 mm) that go.
Then the CPU time of the configured setting on each cloud.

    .venv/bin/python bench/bench_cleaning.py [--seeds 0 1 2] [--sensor tof]
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
from scipy.spatial import cKDTree  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from harness_clouds import observe  # noqa: E402

from hsqbench.planner.cleaning import CleaningConfig, isolated_mask  # noqa: E402
from hsqbench.planner.hsq.config import resolve_config  # noqa: E402

FAR_M = 0.01
SURFACE_M = 0.004


def main() -> int:
    from hsqbench.assets.library import ycb_names

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--sensor", default="tof")
    args = parser.parse_args()

    clouds = []
    for name in ycb_names():
        for seed in args.seeds:
            obs = observe(name, seed, args.sensor, False)
            dist, _ = cKDTree(obs["truth"]).query(obs["points"])
            clouds.append((obs["points"], dist))
    dist = np.concatenate([d for _, d in clouds])
    print(
        f"{len(clouds)} clouds, {dist.size} points: {np.mean(dist > FAR_M):.2%} farther than "
        f"{FAR_M * 1000:.0f} mm from the mesh, {np.mean(dist <= SURFACE_M):.2%} within "
        f"{SURFACE_M * 1000:.0f} mm"
    )
    print(f"{'radius':>8} {'min_nb':>6} {'far kept':>10} {'surface dropped':>16}")
    for radius in (0.006, 0.008, 0.010):
        for n in (3, 5, 8):
            cfg = CleaningConfig(radius_m=radius, min_neighbours=n)
            drop = np.concatenate([isolated_mask(p, cfg) for p, _ in clouds])
            far, surface = dist > FAR_M, dist <= SURFACE_M
            print(
                f"{radius * 1000:6.0f}mm {n:6d} {np.mean(~drop[far]):10.2%} "
                f"{np.mean(drop[surface]):16.2%}"
            )

    cfg = resolve_config(None).cleaning
    times = []
    for points, _ in clouds:
        start = time.process_time()
        isolated_mask(points, cfg)
        times.append((points.shape[0], time.process_time() - start))
    sizes, cpu = np.array(times).T
    big = sizes >= 10_000
    print(
        f"configured r={cfg.radius_m} m, n={cfg.min_neighbours}: CPU median "
        f"{np.median(cpu) * 1000:.1f} ms, clouds >= 10k points: "
        f"{np.median(cpu[big]) * 1000 if big.any() else float('nan'):.1f} ms"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
