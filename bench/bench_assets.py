"""Time the object-library build (CoACD decomposition, inertia, MuJoCo meshes) in a fresh cache.

Default (part of `make bench`): the five procedural objects and, when HSQ_YCB_DIR is set, the
YCB mug (the slowest scan to decompose), one process. `--all --jobs 2`: the whole library as
`hsqbench assets build --jobs 2` would build it, for the figures in the build report.

    .venv/bin/python bench/bench_assets.py [--all] [--jobs N] [NAMES...]
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*")
    parser.add_argument("--all", action="store_true", help="every known object")
    parser.add_argument("--jobs", type=int, default=1)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="hsq-bench-assets-") as cache:
        os.environ["HSQ_CACHE_DIR"] = cache  # a fresh cache: every object is really built
        from hsqbench.assets.library import build_objects, object_names

        if args.all:
            names = object_names()
        elif args.names:
            names = args.names
        else:
            names = object_names("procedural") + (["mug"] if "mug" in object_names("ycb") else [])
        start = time.perf_counter()
        assets = build_objects(names, jobs=args.jobs, progress=False)
        wall = time.perf_counter() - start
        print(
            f"{'object':22s} {'hulls':>5s} {'build_s':>8s} {'cpu_s':>8s} {'coacd_s':>8s}  inertia"
        )
        for a in assets:
            info = a.info
            print(
                f"{a.name:22s} {len(a.collision_meshes):5d} {info['build_s']:8.1f} "
                f"{info['build_cpu_s']:8.1f} "
                f"{info['coacd_s']:8.1f}  {info['inertia_method']}"
                + ("" if info["collision_method"] == "coacd" else "  (convex-hull fallback)")
            )
        total = sum(a.info["build_s"] for a in assets)
        cpu = sum(a.info["build_cpu_s"] for a in assets)
        print(
            f"{len(assets)} objects: {wall:.1f} s wall with {args.jobs} job(s); per-object "
            f"times summed: {total:.1f} s wall, {cpu:.1f} s CPU"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
