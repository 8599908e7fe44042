"""What the vgn and giga planners' choices cost, on one simulated observation per scene kind.

For an isolated mustard bottle, a packed and a pile scene (seed 0 of the default configs):
how many 0.30 m cubes the planners tile, how much of the cleaned cloud their kept squares cover
against one cube at the cloud's centre, the median timings of three plans per planner (TSDF,
network, detection, total), and GIGA's decoders queried only where the detection reads against
all voxels (time, and whether the detections are identical). Needs torch and the weights
(``HSQ_MODELS_DIR``). Usage::

    python bench/bench_volumetric.py

The table in docs/learned-baselines.md came from this script.
"""

from __future__ import annotations

import time

import numpy as np

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.base import clean_input
from hsqbench.planner.learned import detection, tsdf
from hsqbench.planner.learned.giga_net import predict_giga
from hsqbench.planner.learned.volumetric import VolumetricPlanner, cube_origins
from hsqbench.sim.trial.config import load_trial_config
from hsqbench.sim.trial.env import TrialEnv

SCENES = (("isolated", "mustard_bottle"), ("packed", None), ("pile", None))


def covered(points: np.ndarray, origins: np.ndarray, cfg) -> float:
    """Share of ``points`` inside some cube's kept square."""
    b = detection.bound_voxels(cfg.detection, cfg.grid.voxel_m)[0] * cfg.grid.voxel_m
    span = (cfg.grid.voxels - 1) * cfg.grid.voxel_m - b
    lo, hi = origins[:, None, :2] + b, origins[:, None, :2] + span
    inside = np.all((points[None, :, :2] >= lo) & (points[None, :, :2] <= hi), axis=2)
    return float(inside.any(axis=0).mean())


def giga_restricted_vs_full(planner, views, origins) -> str:
    cfg = planner.config
    grids = [
        tsdf.integrate(
            views,
            o,
            cfg.grid.voxel_m,
            (cfg.grid.voxels,) * 3,
            cfg.grid.truncation_voxels * cfg.grid.voxel_m,
        )
        for o in origins
    ]
    x = np.stack([g.network_input() for g in grids])
    valid = np.stack([detection.valid_centres(v, cfg.detection) for v in x])
    needed = np.stack([detection.smoothing_support(v, cfg.detection) for v in valid])
    net, device = planner.nets["packed"], planner.device
    tick = time.perf_counter()
    part = predict_giga(net, x, needed, device)
    part_s = time.perf_counter() - tick
    tick = time.perf_counter()
    full = predict_giga(net, x, np.ones_like(needed), device)
    full_s = time.perf_counter() - tick
    same = all(
        np.array_equal(
            detection.detect(
                part[0][i], part[2][i], valid[i], cfg.detection, cfg.grid.voxel_m
            ).index,
            detection.detect(
                full[0][i], full[2][i], valid[i], cfg.detection, cfg.grid.voxel_m
            ).index,
        )
        for i in range(len(x))
    )
    return (
        f"giga decoders at {needed.mean():.1%} of voxels: {part_s:.2f} s vs all voxels "
        f"{full_s:.2f} s; same detections: {same}"
    )


def main() -> None:
    cfg = load_trial_config()
    planners = {n: VolumetricPlanner(n) for n in ("vgn", "giga")}
    vcfg = planners["vgn"].config
    for kind, obj in SCENES:
        with TrialEnv.build(kind, obj, 0, cfg) as env:
            obs = env.observe()
            points = np.asarray(obs.points)
            plane = np.asarray(env.info.support_plane)
            context = PlanningContext(
                support_plane=tuple(plane), depth_views=obs.cameras, scene=kind
            )
            clean = clean_input(points, planners["vgn"].cleaning_config()).points
            origins, _ = cube_origins(clean, plane, vcfg)
            central, _ = cube_origins(clean.mean(axis=0, keepdims=True), plane, vcfg)
            print(
                f"{kind}: {len(env.info.objects)} object(s), {len(origins)} cube(s), cloud in "
                f"kept squares {covered(clean, origins, vcfg):.1%} (one central cube: "
                f"{covered(clean, central, vcfg):.1%})"
            )
            for name, planner in planners.items():
                runs = [planner.plan(points, context) for _ in range(3)]
                med = {k: float(np.median([r.timings[k] for r in runs])) for k in runs[0].timings}
                timing = ", ".join(f"{k} {v:.3f} s" for k, v in med.items())
                print(f"  {name}: {len(runs[0].grasps)} grasps; {timing}")
            print("  " + giga_restricted_vs_full(planners["giga"], obs.cameras, origins))


if __name__ == "__main__":
    main()
