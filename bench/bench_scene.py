"""Time scene building and simulation, and measure the hand's hold on each object.

Prints: ``build_scene`` wall time and simulated settle time for isolated and packed scenes,
simulation speed of a packed scene (steps per second, real-time factor), and the hold test
(close, lift 15 cm at 1.5 m/s^2, hold 2 s) per object: grasp, squeeze force, slip.
Objects must be built already or are built on first use (see bench_assets.py).

    .venv/bin/python bench/bench_scene.py [--seeds N] [--hold NAMES...]
"""

from __future__ import annotations

import sys
from pathlib import Path as _Path

# The test scaffolding (tests/fake_backend.py, tests/hold_rig.py) lives with the tests.
sys.path.insert(0, str(_Path(__file__).resolve().parents[1]))

import argparse
import time


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="packed scenes to build")
    parser.add_argument("--hold", nargs="*", default=None, help="objects (default: 15 YCB)")
    args = parser.parse_args()

    import mujoco

    from hsqbench.assets.library import get_object, ycb_names
    from hsqbench.settings import ycb_dir
    from hsqbench.sim.scene import build_scene
    from tests.hold_rig import find_top_down_grasp, run_hold_test

    have_ycb = ycb_dir(required=False) is not None
    fallback = ["proc_box", "proc_cylinder", "proc_l", "proc_mug", "proc_sphere"]
    for seed in range(args.seeds):
        objects = None if have_ycb else fallback
        model, data, info = build_scene("packed", objects, seed=seed)
        print(
            f"packed seed {seed}: {', '.join(info.objects)}: build {info.build_time_s:.2f} s, "
            f"settled in {info.settle_time_s:.2f} s simulated"
        )
    t0 = time.perf_counter()
    n = 2000
    for _ in range(n):
        mujoco.mj_step(model, data)
    wall = time.perf_counter() - t0
    sim = n * model.opt.timestep
    print(f"packed scene: {n / wall:.0f} steps/s, real-time factor {sim / wall:.1f}")
    _, _, iso = build_scene("isolated", None if have_ycb else ["proc_box"], seed=0)
    print(f"isolated seed 0 ({iso.objects[0]}): build {iso.build_time_s:.2f} s")

    names = args.hold if args.hold is not None else (ycb_names() if have_ycb else fallback)
    print(f"{'object':22s} {'mass kg':>8s} {'width mm':>9s} {'force N':>13s} {'slip mm':>8s} held")
    for name in names:
        obj = get_object(name)
        result = run_hold_test(obj, find_top_down_grasp(obj))
        f = result.finger_force_n
        print(
            f"{name:22s} {obj.mass_kg:8.3f} {1000 * result.width_m:9.1f} "
            f"{f[0]:6.1f} {f[1]:6.1f} {1000 * result.slip_m:8.2f} {result.held}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
