"""The learned planners on a GPU against the CPU: the one short check for a machine with CUDA.

Plans one synthetic scene (exact depth images of two boxes on a table from the harness's two
camera positions, ``tests/volumetric_scene.py``) with ``vgn`` and ``giga`` (isolated, packed
weights; pile, pile weights) and ``contact-graspnet`` (on the cloud back-projected from the same
images), once with ``device: cpu`` and once with ``--device``, and prints per planner and scene:
the grasps each device found, the distance between their top grasps, and the planning time of
each (the median of ``--repeats`` plans after one warm-up plan). Exit 1 when torch does not see
the device, or when a top grasp moves more than ``--tolerance-m`` (one 7.5 mm voxel by default:
float32 kernels differ by rounding, which may reorder near-equal maxima but not move the best
grasp across the box).

    .venv/bin/python bench/check_cuda.py                 # on a machine with CUDA
    .venv/bin/python bench/check_cuda.py --device cpu    # the check itself, anywhere (a test runs it)

Needs torch and the weights (``HSQ_MODELS_DIR``); ``contact-graspnet`` also the rest of the
learned extra. On a lent GPU machine whose python3 has a CUDA torch (and numpy, scipy, yaml) but
not hsqbench's other dependencies, vgn and giga run from the checkout: copy the weights into an
ignored folder here (``mkdir -p .dev && cp -r ../shared/models .dev/``, ``.dev/`` in
``.git/info/exclude``), carry it, and run ``PYTHONPATH=. HSQ_MODELS_DIR=.dev/models python3
bench/check_cuda.py --planners vgn giga``.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hsqbench.planner.api import PlanningContext
from tests.volumetric_scene import CAMERAS, TABLE, box_scene

#: Two boxes 0.25 m apart: one cube each for vgn and giga, two objects for Contact-GraspNet.
BOXES = [
    (np.array([0.46, -0.145, 0.0]), np.array([0.54, -0.095, 0.08])),
    (np.array([0.47, 0.09, 0.0]), np.array([0.53, 0.15, 0.12])),
]
#: Points lower than this over the table are the table (the harness crops it the same way).
TABLE_MARGIN_M = 0.005


def back_project(views) -> np.ndarray:
    """World points of every measured pixel above the table (the planners' cloud). The same
    arithmetic as ``hsqbench.sim.camera.backproject``, written out here because that module
    imports mujoco, which the lent GPU machines' image does not hold."""
    clouds = []
    for view in views:
        v, u = np.nonzero(view.depth_m > 0)
        z = view.depth_m[v, u].astype(np.float64)
        cam = np.column_stack(
            [(u - view.K[0, 2]) / view.K[0, 0] * z, (v - view.K[1, 2]) / view.K[1, 1] * z, z]
        )
        world = cam @ view.T_world_camera[:3, :3].T + view.T_world_camera[:3, 3]
        clouds.append(world[world[:, 2] > TABLE_MARGIN_M])
    return np.concatenate(clouds)


def build(name: str, device: str):
    """The planner ``name`` with its config's ``device`` set."""
    if name == "contact-graspnet":
        from hsqbench.planner.learned.config import resolve_contact_graspnet_config
        from hsqbench.planner.learned.contact_graspnet import ContactGraspNetPlanner

        cfg = dataclasses.replace(resolve_contact_graspnet_config(None), device=device)
        return ContactGraspNetPlanner(cfg)
    from hsqbench.planner.learned.volumetric import VolumetricPlanner
    from hsqbench.planner.learned.volumetric_config import resolve_volumetric_config

    cfg = dataclasses.replace(resolve_volumetric_config(None), device=device)
    return VolumetricPlanner(name, cfg)


def plan_timed(planner, cloud, context, repeats: int):
    """(result of the last plan, median seconds over ``repeats`` after one warm-up plan)."""
    planner.plan(cloud, context)
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = planner.plan(cloud, context)
        times.append(time.perf_counter() - start)
    return result, float(np.median(times))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="cuda", help="the device to check against the CPU")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tolerance-m", type=float, default=0.0075)
    parser.add_argument(
        "--planners", nargs="+", default=["vgn", "giga", "contact-graspnet"], metavar="NAME"
    )
    args = parser.parse_args(argv)
    import torch

    print(f"torch {torch.__version__}, CUDA available: {torch.cuda.is_available()}")
    if args.device.startswith("cuda"):
        if not torch.cuda.is_available():
            print(f"{args.device}: torch sees no CUDA device; nothing to check", file=sys.stderr)
            return 1
        print(f"device: {torch.cuda.get_device_name(0)}")
    views = box_scene(BOXES)
    cloud = back_project(views)
    failed = []
    print("planner           scene     grasps cpu/dev  top grasp moved  cpu s  dev s")
    for name in args.planners:
        cpu, dev = build(name, "cpu"), build(name, args.device)
        scenes = ("isolated", "pile") if name != "contact-graspnet" else ("isolated",)
        for scene in scenes:
            context = PlanningContext(
                support_plane=TABLE,
                seed=0,
                scene=scene,
                depth_views=views,
                camera_positions=CAMERAS,
            )
            a, t_cpu = plan_timed(cpu, cloud, context, args.repeats)
            b, t_dev = plan_timed(dev, cloud, context, args.repeats)
            if a.grasps and b.grasps:
                moved = float(np.linalg.norm(a.grasps[0].position - b.grasps[0].position))
            else:
                moved = 0.0 if not (a.grasps or b.grasps) else float("inf")
            bad = moved > args.tolerance_m
            print(
                f"{name:17s} {scene:9s} {len(a.grasps):5d}/{len(b.grasps):<5d}   "
                f"{1000 * moved:8.2f} mm{'  <- differs' if bad else ''}   {t_cpu:5.2f}  {t_dev:5.2f}"
            )
            if bad:
                failed.append(f"{name} ({scene})")
    if failed:
        print(f"top grasps differ between cpu and {args.device}: {', '.join(failed)}")
        return 1
    print(f"every top grasp on {args.device} within {1000 * args.tolerance_m:g} mm of the CPU's")
    return 0


if __name__ == "__main__":
    sys.exit(main())
