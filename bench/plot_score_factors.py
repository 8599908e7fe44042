"""Spread of the four score factors on realistic clouds of the 15 YCB objects.

Each object stands upright at a seeded yaw at the workspace centre; two depth cameras at the
scene's poses (configs/scene.yaml: 0.8 m to either side, 0.5 m up) see it. The cloud is the mesh
surface sampled every 2 mm, kept where a camera sees it (z-buffer, tests/shapes.visible_mask),
with the table band (lowest 5 mm) removed, 1 mm Gaussian noise and 2 mm voxels, as the perception
module produces. The full planner runs on it; the raw measures (alpha, beta, gamma, delta) and
factors of every surviving closing line are collected.

Output: a PNG of histograms and a JSON of percentiles in ``--out`` (default
``results/factor_spread``), and a table on stdout. Needs HSQ_YCB_DIR.

    .venv/bin/python bench/plot_score_factors.py [--yaws 2] [--out DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hsqbench.planner import plan_grasps
from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.hsq.config import load_planner_config
from hsqbench.settings import RESULTS_DIR, ycb_dir
from tests.shapes import visible_mask

CENTRE = np.array([0.5, 0.0, 0.0])
CAMERAS = np.array([[0.62, 0.78, 0.55], [0.62, -0.78, 0.55]])
SPACING_M = 0.002
NOISE_M = 0.001
TABLE_BAND_M = 0.005
VOXEL_M = 0.002


def ycb_cloud(mesh_path: Path, yaw: float, rng: np.random.Generator) -> np.ndarray:
    """Two-camera cloud of a YCB mesh standing at the workspace centre (metres)."""
    import trimesh

    mesh = trimesh.load(mesh_path, force="mesh", process=False)
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    verts = mesh.vertices @ rot.T
    verts[:, :2] -= verts[:, :2].mean(axis=0)
    verts[:, 2] -= verts[:, 2].min()
    mesh = trimesh.Trimesh(verts + CENTRE, mesh.faces, process=False)
    n = int(mesh.area / SPACING_M**2)
    points, faces = trimesh.sample.sample_surface(mesh, n, seed=int(rng.integers(1 << 31)))
    normals = mesh.face_normals[faces]
    seen = np.zeros(len(points), dtype=bool)
    for camera in CAMERAS:
        seen |= visible_mask(points, normals, camera)
    points = points[seen & (points[:, 2] > TABLE_BAND_M)]
    points = points + rng.normal(scale=NOISE_M, size=points.shape)
    return voxel_downsample(points, VOXEL_M).points


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--yaws", type=int, default=2, help="random yaws per object")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=RESULTS_DIR / "factor_spread")
    parser.add_argument("--save", action="store_true", help="also save each cloud as .npy")
    parser.add_argument("--only", nargs="*", help="only these objects")
    args = parser.parse_args()
    root = ycb_dir()
    names = sorted(p.parent.name for p in root.glob("*/textured.obj"))
    names = [n for n in names if not args.only or n in args.only]
    config = load_planner_config()
    rng = np.random.default_rng(args.seed)
    rows: dict[str, list[float]] = {k: [] for k in ("alpha_m", "beta", "gamma", "delta_m")}
    factors: dict[str, list[float]] = {k: [] for k in ("h_alpha", "h_beta", "h_gamma", "h_delta")}
    hidden_alpha, hidden_scale, best, times = [], [], [], []
    for name in names:
        for _ in range(args.yaws):
            cloud = ycb_cloud(root / name / "textured.obj", rng.uniform(0, 2 * np.pi), rng)
            if args.save:
                args.out.mkdir(parents=True, exist_ok=True)
                np.save(args.out / f"{name}_{len(times)}.npy", cloud)
            start = time.perf_counter()
            result = plan_grasps(cloud, config, support_plane=(0, 0, 1, 0), seed=args.seed)
            times.append(time.perf_counter() - start)
            hidden_alpha += [h.alpha for h in result.hidden_superquadrics]
            hidden_scale += [
                float(np.cbrt(np.prod(h.superquadric.scale))) for h in result.hidden_superquadrics
            ]
            cands = result.candidates
            first = np.flatnonzero(cands.kept & (cands.roll_index == 0) | cands.kept)
            lines = np.unique(cands.line_index[first])
            pick = lines * cands.n_roll + np.argmax(
                cands.kept.reshape(len(cands.lines), -1)[lines], axis=1
            )
            for k in rows:
                rows[k] += cands.measures[k][pick].tolist()
            for k in factors:
                factors[k] += cands.factors[k][pick].tolist()
            top = result.grasps[0] if result.grasps else None
            best.append(top.score if top else 0.0)
            print(
                f"{name:22s} {len(cloud):6d} pts  {len(result.hidden_superquadrics):2d} sq  "
                f"{len(lines):4d} lines  best {best[-1]:.3f}  {times[-1]:.2f} s  "
                + " ".join(f"{k}:{v}" for k, v in result.remaining.items()),
                flush=True,
            )
    summary = {}
    print(f"\n{'measure':10s} {'p5':>9s} {'p25':>9s} {'p50':>9s} {'p75':>9s} {'p95':>9s}")
    for k, v in {**rows, **factors, "hidden_alpha_m": hidden_alpha}.items():
        q = np.percentile(np.asarray(v, dtype=float), [5, 25, 50, 75, 95]).tolist()
        summary[k] = q
        print(f"{k:10s} " + " ".join(f"{x:9.4g}" for x in q))
    # The unit question for alpha, on every hidden superquadric (not only survivors).
    a, size = np.asarray(hidden_alpha), np.asarray(hidden_scale)
    q = config.grasp.q_alpha
    print("\nh_alpha over all hidden superquadrics (p5 p50 p95) if alpha were measured in:")
    for label, value in (
        ("metres", a),
        ("millimetres", a * 1e3),
        ("decimetres (alpha_unit_m = 0.1)", a / 0.1),
        ("units of the sq's size (cbrt(ax ay az))", a / size),
    ):
        h = np.exp(-(value**2) / q)
        summary[f"h_alpha[{label}]"] = np.percentile(h, [5, 50, 95]).tolist()
        print(f"  {label:42s} " + " ".join(f"{x:8.3g}" for x in np.percentile(h, [5, 50, 95])))
    print(f"planner time per cloud: median {np.median(times):.2f} s")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "factor_spread.json").write_text(
        json.dumps({"percentiles_5_25_50_75_95": summary, "n_lines": len(rows["beta"])}, indent=2)
    )
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 4, figsize=(16, 7))
    for ax, (k, v) in zip(axes[0], rows.items(), strict=True):
        ax.hist(np.asarray(v), bins=40)
        ax.set_title(k)
    for ax, (k, v) in zip(axes[1], factors.items(), strict=True):
        ax.hist(np.asarray(v), bins=np.linspace(0, 1, 41))
        ax.set_title(k)
    fig.suptitle(f"score factors over {len(rows['beta'])} surviving closing lines, 15 YCB objects")
    fig.tight_layout()
    fig.savefig(args.out / "factor_spread.png", dpi=100)
    print(f"wrote {args.out / 'factor_spread.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
