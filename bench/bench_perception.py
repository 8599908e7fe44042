"""Time one perception observation (two depth renders, sensor errors, fused cloud) per sensor model.

Scenes: an isolated procedural box (also the accuracy of its noiseless fused cloud) and a packed
scene of the five procedural objects. Renderers are made once per scene (their creation is
timed separately) and reused for every observation, as the harness does. Wall time depends on
the load of the machine; CPU time (all threads of this process, EGL rendering included) less so.

    MUJOCO_GL=egl .venv/bin/python bench/bench_perception.py [--repeats N] [--isolated-only]
"""

from __future__ import annotations

import argparse
import os
import time
from dataclasses import replace

import numpy as np

MODELS = ("none", "tof", "calibration", "tof+calibration")
PACKED = ("proc_box", "proc_cylinder", "proc_sphere", "proc_l", "proc_mug")


def box_distance(points: np.ndarray, rotation: np.ndarray, centre: np.ndarray, half) -> np.ndarray:
    """Unsigned distance (m) of points to the surface of a box."""
    q = np.abs((points - centre) @ rotation) - np.asarray(half)
    return np.linalg.norm(np.maximum(q, 0.0), axis=1) - np.minimum(q.max(axis=1), 0.0)


def bench_scene(label: str, kind: str, objects, repeats: int) -> None:
    from hsqbench.sim.perception import Perception, load_perception_config
    from hsqbench.sim.scene import build_scene

    model, data, info = build_scene(kind, objects, seed=1)
    base = load_perception_config()
    print(f"\n== {label}: {', '.join(info.objects)}")
    print(
        f"{'sensor_model':16s} {'points':>6s} {'wall_s':>7s} {'cpu_s':>7s} {'render':>7s} "
        f"{'noise':>7s} {'cloud':>7s} {'down':>7s}   (medians over {repeats})"
    )
    for name in MODELS:
        t, c = time.perf_counter(), time.process_time()
        perception = Perception.from_scene(
            model, info, rng=np.random.default_rng(0), config=replace(base, sensor_model=name)
        )
        make_wall, make_cpu = time.perf_counter() - t, time.process_time() - c
        with perception:
            perception.observe(data, np.random.default_rng(0))  # warm-up
            rows, walls, cpus = [], [], []
            for k in range(repeats):
                t, c = time.perf_counter(), time.process_time()
                obs = perception.observe(data, np.random.default_rng(k))
                walls.append(time.perf_counter() - t)
                cpus.append(time.process_time() - c)
                tm = obs.timings
                rows.append((tm.render_s, tm.noise_s, tm.cloud_s, tm.downsample_s))
        med = np.median(np.array(rows), axis=0)
        print(
            f"{name:16s} {len(obs.points):6d} {np.median(walls):7.3f} {np.median(cpus):7.3f} "
            + " ".join(f"{x:7.3f}" for x in med)
            + f"   (renderers made in {make_wall:.2f} s wall, {make_cpu:.2f} s CPU)"
        )
        if name == "none" and info.objects == ["proc_box"]:
            body = info.object_body_ids["proc_box"]
            R = data.xmat[body].reshape(3, 3)
            centre = data.xpos[body] + R @ np.array([0.0, 0.0, 0.05])
            d = box_distance(obs.points, R, centre, (0.025, 0.035, 0.05))
            print(
                f"   noiseless box cloud: distance to the true surface max {d.max() * 1e3:.2f} mm, "
                f"p99 {np.percentile(d, 99) * 1e3:.2f} mm, mean {d.mean() * 1e3:.3f} mm; "
                f"points per camera {np.bincount(obs.camera_index).tolist()}"
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--isolated-only", action="store_true")
    args = parser.parse_args()
    os.environ.setdefault("MUJOCO_GL", "egl")
    os.environ.setdefault("PYOPENGL_PLATFORM", "egl")
    bench_scene("isolated", "isolated", "proc_box", args.repeats)
    if not args.isolated_only:
        bench_scene("packed", "packed", list(PACKED), args.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
