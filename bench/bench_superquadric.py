"""Time the superquadric geometry the planner calls per superquadric: surface sampling, alpha/beta,
Gaussian curvature, plus the quality of the sampling (evenness, largest hole).

Shapes: 3, 6 and 10 cm objects (box-like, ellipsoid, cylinder, pinched), spacings 2, 3 and 5 mm; the
cloud for alpha/beta is a noisy 1.5 mm sampling of half the surface (what one camera side sees).
Prints wall-clock medians over repeats (the machine may be shared: CPU time is printed as well).

    .venv/bin/python bench/bench_superquadric.py [--repeats N]
"""

from __future__ import annotations

import argparse
import time
from functools import partial

import numpy as np
from scipy.spatial import cKDTree

from hsqbench.superquadric.fit import alpha_beta
from hsqbench.superquadric.geometry import Superquadric

SHAPES = {
    "box": (0.1, 0.1, (0.4, 0.6, 1.0)),
    "ellipsoid": (1.0, 1.0, (0.5, 0.7, 1.0)),
    "cylinder": (0.1, 1.0, (0.5, 0.5, 1.0)),
    "pinched": (1.5, 1.8, (0.6, 0.8, 1.0)),
}
SIZES_M = (0.03, 0.06, 0.10)  # largest dimension of the object (2 x largest semi-axis)
SPACINGS_M = (0.002, 0.003, 0.005)


def timed(func, repeats: int) -> tuple[float, float]:
    """Median wall and CPU milliseconds of ``func()``."""
    func()
    wall, cpu = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        func()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return 1e3 * float(np.median(wall)), 1e3 * float(np.median(cpu))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    header = (
        f"{'shape':10s} {'size_cm':>7s} {'sp_mm':>5s} {'n_S':>6s} {'n_Y':>6s} "
        f"{'sample_ms':>9s} {'cpu':>5s} {'ab_ms':>6s} {'cpu':>5s} {'curv_ms':>7s} "
        f"{'nn/sp':>5s} {'nn_cv':>5s} {'hole/sp':>7s}"
    )
    print(header)
    for name, (e1, e2, ratios) in SHAPES.items():
        for size in SIZES_M:
            scale = 0.5 * size * np.array(ratios)
            sq = Superquadric(e1, e2, scale)
            dense, _ = sq.sample_surface(0.0015)
            half = dense[dense[:, 0] > 0]
            cloud = half + rng.normal(0.0, 0.001, half.shape)
            for spacing in SPACINGS_M:
                samples, _ = sq.sample_surface(spacing)
                s_wall, s_cpu = timed(partial(sq.sample_surface, spacing), args.repeats)
                fit = partial(alpha_beta, cloud, sq, spacing, 2.0 * spacing)
                ab_wall, ab_cpu = timed(fit, args.repeats)
                k_wall, _ = timed(partial(sq.gaussian_curvature, samples), args.repeats)
                nn = cKDTree(samples).query(samples, k=2)[0][:, 1]
                hole = cKDTree(samples).query(dense)[0].max()
                print(
                    f"{name:10s} {100 * size:7.0f} {1e3 * spacing:5.0f} {len(samples):6d} "
                    f"{len(cloud):6d} {s_wall:9.2f} {s_cpu:5.1f} {ab_wall:6.2f} {ab_cpu:5.1f} "
                    f"{k_wall:7.2f} {nn.mean() / spacing:5.2f} {nn.std() / nn.mean():5.2f} "
                    f"{hole / spacing:7.2f}"
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
