"""How to feed the harness's cloud to Contact-GraspNet: input frame, views, density, table patch.

For each adapter variant (the other settings as in ``configs/contact_graspnet.yaml``; "table":
a 30 cm table patch) and each harness cloud (the two-camera clouds of isolated YCB objects,
rendered and cached by ``eval_planner_ycb.observe``), runs the ``contact-graspnet`` planner with
the harness's elimination rules on and reports, over the clouds:

- ``grasps``: median number of network grasps over the confidence threshold;
- ``on surface``: share of the top-10 grasps whose two contacts (``P_G -/+ width/2 closing``)
  both lie within 5 mm of the object's true surface (mesh samples);
- ``pass rules``: share of the top-10 grasps that survive the harness's rules (width, support,
  table, collision, sweep; the rules hsq and the baselines must pass);
- ``s``: median planning time (one thread).

Needs the learned extra (``make learned``) and HSQ_YCB_DIR. Usage::

    python bench/eval_contact_graspnet.py --objects cracker_box mug --seeds 0 1
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from eval_planner_ycb import observe

from hsqbench.planner.learned.config import load_contact_graspnet_config
from hsqbench.planner.learned.contact_graspnet import plan_contact_graspnet

NO_TABLE = {"table_patch_radius_m": 0.0}
TABLE = {"table_patch_radius_m": 0.3}
VARIANTS = {
    "world centred, fused": NO_TABLE,
    "camera frame, fused": {**NO_TABLE, "input_frame": "camera"},
    "world centred, per camera": {**NO_TABLE, "views": "per_camera"},
    "world centred, fused, package width": {**NO_TABLE, "width_source": "network"},
    "world centred, fused, table": TABLE,
    "world centred, per camera, table": {**TABLE, "views": "per_camera"},
    "world centred, fused, table, 3 mm voxels": {**TABLE, "input_voxel_m": 0.003},
    "world centred, fused, table, package width": {**TABLE, "width_source": "network"},
    "camera frame, fused, table": {**TABLE, "input_frame": "camera"},
}
TOP = 10
SURFACE_TOL_M = 0.005


def measure(obs: dict, cfg, seed: int) -> dict[str, float]:
    start = time.perf_counter()
    res = plan_contact_graspnet(
        obs["points"],
        dataclasses.replace(cfg, eliminate=True),
        support_plane=obs["support_plane"],
        seed=seed,
        camera_positions=obs["camera_positions"],
    )
    seconds = time.perf_counter() - start
    cands = res.candidates
    n = len(cands)
    top = np.arange(min(TOP, n))  # candidates are in confidence order
    if top.size == 0:
        return {"grasps": 0, "on_surface": 0.0, "pass": 0.0, "s": seconds}
    centres = cands.lines.centres[top]
    offset = cands.lines.half_lengths[top, None] * cands.lines.directions[top]
    tree = cKDTree(obs["truth"])
    d_a, _ = tree.query(centres - offset)
    d_b, _ = tree.query(centres + offset)
    on_surface = (d_a < SURFACE_TOL_M) & (d_b < SURFACE_TOL_M)
    return {
        "grasps": n,
        "on_surface": float(on_surface.mean()),
        "pass": float(cands.kept[top].mean()),
        "s": seconds,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", nargs="+", default=["cracker_box", "mustard_bottle", "mug"])
    parser.add_argument("--seeds", nargs="+", type=int, default=[0])
    parser.add_argument(
        "--threshold", type=float, default=None, help="override confidence_threshold"
    )
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    args = parser.parse_args()
    base = load_contact_graspnet_config()
    if args.threshold is not None:
        base = dataclasses.replace(base, confidence_threshold=args.threshold)
    clouds = [(o, s, observe(o, s, None, refresh=False)) for o in args.objects for s in args.seeds]
    print(f"{len(clouds)} clouds: {', '.join(f'{o} s{s}' for o, s, _ in clouds)}")
    print("| variant | grasps | on surface | pass rules | s |")
    print("| --- | --- | --- | --- | --- |")
    for name in args.variants:
        cfg = dataclasses.replace(base, **VARIANTS[name])
        rows = [measure(obs, cfg, seed) for _, seed, obs in clouds]
        col = {k: np.array([r[k] for r in rows]) for k in rows[0]}
        print(
            f"| {name} | {np.median(col['grasps']):.0f} | {col['on_surface'].mean():.2f} | "
            f"{col['pass'].mean():.2f} | {np.median(col['s']):.2f} |"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
