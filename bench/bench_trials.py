"""Trial throughput: isolated trials per second in one process (``--jobs 1``), and what making
a trial's depth renderer costs: with a GL context of its own, with the process's one, and with
the uploads kept from the same object in another pose.

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


def renderer_cost(objects: list[str], repeats: int) -> tuple[float, float, float]:
    """Median seconds to make and free the renderer of one built scene (one image size, as the
    two cameras share it): a fresh ``mujoco.Renderer`` (its own GL context: the code before
    issue 17), a :class:`DepthRenderer` after one of another object (the process's GL context,
    the meshes uploaded), and one after the same object in another pose (the uploads kept).
    The objects take turns, so the second needs two or more of them."""
    import mujoco

    from hsqbench.sim.depth_renderer import DepthRenderer
    from hsqbench.sim.scene import build_scene

    scenes = []
    for obj in objects:
        model, _, info = build_scene("isolated", obj, seed=0)
        moved, _, _ = build_scene("isolated", obj, seed=1)
        cam = info.depth_cameras[0]
        scenes.append((model, moved, cam.height_px, cam.width_px))
    fresh, uploaded, kept = [], [], []
    for _ in range(repeats):
        for model, moved, h, w in scenes:
            t0 = time.perf_counter()
            mujoco.Renderer(model, h, w).close()
            t1 = time.perf_counter()
            DepthRenderer(model, h, w).close()
            t2 = time.perf_counter()
            DepthRenderer(moved, h, w).close()
            fresh.append(t1 - t0)
            uploaded.append(t2 - t1)
            kept.append(time.perf_counter() - t2)
    if len(scenes) < 2:  # the same object each turn: nothing was uploaded after the first
        uploaded = uploaded[:1]
    return float(np.median(fresh)), float(np.median(uploaded)), float(np.median(kept))


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
    fresh, uploaded, kept = renderer_cost(args.objects, 4)
    print(
        f"  making a trial's renderer: {1000 * fresh:.0f} ms with its own GL context "
        f"(mujoco.Renderer), {1000 * uploaded:.0f} ms with the process's (DepthRenderer), "
        f"{1000 * kept:.0f} ms after the same object in another pose (uploads kept)"
    )


if __name__ == "__main__":
    main()
