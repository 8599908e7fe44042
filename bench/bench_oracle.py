"""Time the oracle's grasp search (target: at most 1 s per scene, one core).

Builds isolated and packed scenes of a protocol's objects in their resting poses, reads the true
hulls as the trial runner does, and times ``OraclePlanner.plan`` and the graspability check
(``feasible_grasps``) on each. Objects must be built (``hsqbench assets build --protocol ycb``).

    .venv/bin/python bench/bench_oracle.py [--protocol ycb] [--isolated 20] [--packed 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--protocol", default="ycb", help="protocol whose objects to use")
    parser.add_argument("--isolated", type=int, default=20, help="isolated scenes")
    parser.add_argument("--packed", type=int, default=5, help="packed scenes of 5 objects")
    args = parser.parse_args()

    from threadpoolctl import threadpool_limits

    from hsqbench.experiment.config import load_experiment_config
    from hsqbench.planner.api import PlanningContext
    from hsqbench.planner.oracle import OraclePlanner, feasible_grasps
    from hsqbench.sim.scene import build_scene, load_scene_config
    from hsqbench.sim.scene_truth import scene_truth

    cfg = load_experiment_config(args.protocol)
    scene = load_scene_config("scene_resting")
    oracle = OraclePlanner()
    rng = np.random.default_rng(0)
    objects = list(cfg.isolated.objects)
    draws = [("isolated", [objects[i % len(objects)]]) for i in range(args.isolated)]
    draws += [("packed", list(rng.choice(objects, 5, replace=False))) for _ in range(args.packed)]
    times: dict[str, list[float]] = {"isolated": [], "packed": []}
    graspable = {"isolated": 0, "packed": 0}
    with threadpool_limits(1):
        for seed, (kind, names) in enumerate(draws):
            try:
                model, data, info = build_scene(kind, names, seed, scene_config=scene)
            except ValueError:
                continue  # a packed draw that cannot be placed apart
            truth = scene_truth(model, data, info.object_geom_ids, names, info.support_plane)
            t0 = time.process_time()
            plan = oracle.plan(
                None, PlanningContext(support_plane=truth.support_plane, truth=truth, seed=seed)
            )
            counts = feasible_grasps(truth, oracle.gripper, oracle.config, seed)
            times[kind].append((time.process_time() - t0) / 2)
            graspable[kind] += any(counts.values())
            print(
                f"{kind:8s} {','.join(names)[:60]:60s} {times[kind][-1]:.3f} s "
                f"{len(plan.grasps)} grasps"
            )
    for kind, t in times.items():
        if t:
            print(
                f"{kind}: {len(t)} scenes, {graspable[kind]} graspable; CPU s per search: "
                f"median {np.median(t):.3f}, max {np.max(t):.3f}"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
