"""Does Contact-GraspNet give the same grasps on CUDA as on the CPU, and how fast is each?

For each saved harness cloud (the ``.npz`` files ``eval_planner_ycb.observe`` caches: points,
support plane, camera positions) and seed, runs on every device in ``--devices``:

- the network alone (``network.run_network``): which input points its farthest point sampling
  picked, and for the contacts both devices picked, the largest difference in grasp position
  (mm), approach/closing axes (deg) and confidence;
- the whole ``contact-graspnet-elim`` planner: how many of its top 10 grasps the first device's
  top 10 contains (same position within 5 mm, axes within 10 deg);
- the median planning time per call, after one warm-up call per device (CUDA start-up and the
  model load are not counted).

Prints the machine (torch, CUDA, GPU), one line per cloud and seed and a verdict; ``--out``
writes all of it as JSON. Exit status 1 when a device's grasps disagree with the first
device's beyond the tolerances, 2 when a device or the extra is missing. Needs the learned extra
(``make learned``). Usage::

    python bench/check_contact_graspnet_devices.py --clouds "$HSQ_CACHE_DIR/eval_planner_ycb" \
        --limit 6 --seeds 0 1 2 --devices cpu cuda --out cuda_check.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import platform
import statistics
import sys
import time
from importlib import metadata
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hsqbench.experiment.machine import cpu_model
from hsqbench.planner.learned import network
from hsqbench.planner.learned.config import load_contact_graspnet_config
from hsqbench.planner.learned.contact_graspnet import plan_contact_graspnet
from hsqbench.settings import code_version

TOP = 10
POSITION_TOL_MM = 5.0  # a grasp "the same" across devices: position ...
AXIS_TOL_DEG = 10.0  # ... and approach and closing axes
MIN_TOP_AGREEMENT = 0.8  # the verdict: at least 8 of the top 10 the same on average


def axis_angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between axes row by row, their signs ignored (atan2: exact near 0 in float32)."""
    a, b = np.broadcast_arrays(a, b)
    sine = np.linalg.norm(np.cross(a, b), axis=-1)
    return np.degrees(np.arctan2(sine, np.abs(np.sum(a * b, axis=-1))))


def machine() -> dict:
    torch, _, _ = network.import_backend()
    info = {
        "python": platform.python_version(),
        "torch": torch.__version__,
        "torch_cuda": torch.version.cuda,
        "cuda_available": torch.cuda.is_available(),
        "code": code_version(),
        "cpu": cpu_model(),
        "threads": torch.get_num_threads(),
    }
    if torch.cuda.is_available():
        info["gpu"] = torch.cuda.get_device_name(0)
    for package in ("torch_geometric", "torch_cluster", "cgn_pytorch"):
        try:
            info[package] = metadata.version(package.replace("_", "-"))
        except metadata.PackageNotFoundError:
            info[package] = None
    return info


def network_diff(cloud: np.ndarray, cfgs: dict, seed: int) -> dict:
    """The raw network outputs of each device (``cfgs``: label -> config) against the first's,
    the cloud centred as the planner's world-centred input frame does."""
    cloud = cloud - cloud.mean(axis=0)
    outs = [
        network.run_network(cloud, c.device, seed, c.max_input_points, c.gripper_depth_m)
        for c in cfgs.values()
    ]
    ref, diffs = outs[0], {}
    for device, out in zip(list(cfgs)[1:], outs[1:], strict=True):
        common, i, j = np.intersect1d(ref.input_index, out.input_index, return_indices=True)
        a, b = ref.poses[i], out.poses[j]
        diffs[device] = {
            "fps_same_share": float(common.size / max(ref.input_index.size, 1)),
            "position_mm": float(np.abs(a[:, :3, 3] - b[:, :3, 3]).max(initial=0.0) * 1e3),
            "approach_deg": float(axis_angle_deg(a[:, :3, 2], b[:, :3, 2]).max(initial=0.0)),
            "closing_deg": float(axis_angle_deg(a[:, :3, 0], b[:, :3, 0]).max(initial=0.0)),
            "confidence": float(np.abs(ref.confidence[i] - out.confidence[j]).max(initial=0.0)),
        }
    return diffs


def top_grasps(result) -> dict[str, np.ndarray]:
    g = list(result.grasps[:TOP])
    return {
        "position": np.array([x.position for x in g]).reshape(-1, 3),
        "approach": np.array([x.rotation[:, 2] for x in g]).reshape(-1, 3),
        "closing": np.array([x.rotation[:, 0] for x in g]).reshape(-1, 3),
    }


def top_agreement(ref: dict, other: dict) -> float:
    """Share of ``other``'s top grasps that ``ref``'s top grasps contain (1.0 when both empty)."""
    n = len(other["position"])
    if n == 0 or len(ref["position"]) == 0:
        return float(n == len(ref["position"]))
    dist = np.linalg.norm(other["position"][:, None] - ref["position"][None], axis=-1) * 1e3
    same = (
        (dist <= POSITION_TOL_MM)
        & (axis_angle_deg(other["approach"][:, None], ref["approach"][None]) <= AXIS_TOL_DEG)
        & (axis_angle_deg(other["closing"][:, None], ref["closing"][None]) <= AXIS_TOL_DEG)
    )
    return float(same.any(axis=1).mean())


def plan(obs: dict, cfg, seed: int) -> tuple[dict, float]:
    start = time.perf_counter()
    res = plan_contact_graspnet(
        obs["points"],
        cfg,
        support_plane=obs["support_plane"],
        seed=seed,
        camera_positions=obs["camera_positions"],
    )
    return top_grasps(res), time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clouds", type=Path, required=True, help="folder of cached .npz clouds")
    parser.add_argument("--limit", type=int, default=6, help="at most this many clouds")
    parser.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    parser.add_argument("--devices", nargs="+", default=["cpu", "cuda"])
    parser.add_argument("--out", type=Path, default=None, help="JSON report")
    args = parser.parse_args()
    files = sorted(args.clouds.glob("*.npz"))[: args.limit]
    if not files:
        parser.error(f"no .npz clouds in {args.clouds}: run bench/eval_planner_ycb.py first")
    try:
        network.import_backend()
    except network.LearnedExtraMissing as exc:
        print(exc)
        return 2
    try:
        resolved = [network.resolve_device(d) for d in args.devices]
    except RuntimeError as exc:
        print(f"missing device: {exc}")
        return 2
    # Labels: a device named twice (cpu cpu: a determinism check) is "cpu", "cpu#2".
    devices = [d if d not in resolved[:k] else f"{d}#{k + 1}" for k, d in enumerate(resolved)]
    base = dataclasses.replace(load_contact_graspnet_config(), eliminate=True)
    cfgs = {
        lab: dataclasses.replace(base, device=d) for lab, d in zip(devices, resolved, strict=True)
    }
    info = machine()
    print(json.dumps(info))
    clouds = {}
    for f in files:
        with np.load(f) as data:
            clouds[f.stem] = {k: data[k] for k in ("points", "support_plane", "camera_positions")}
    for d in devices:  # warm-up: CUDA context and model load
        plan(next(iter(clouds.values())), cfgs[d], 0)
    rows, times = [], {d: [] for d in devices}
    for name, obs in clouds.items():
        for seed in args.seeds:
            tops = {}
            for d in devices:
                tops[d], seconds = plan(obs, cfgs[d], seed)
                times[d].append(seconds)
            row = {
                "cloud": name,
                "seed": seed,
                "network": network_diff(obs["points"], cfgs, seed),
                "top_agreement": {d: top_agreement(tops[devices[0]], tops[d]) for d in devices[1:]},
            }
            rows.append(row)
            print(json.dumps(row), flush=True)
    median_s = {d: statistics.median(t) for d, t in times.items()}
    agreement = {d: float(np.mean([r["top_agreement"][d] for r in rows])) for d in devices[1:]}
    ok = all(a >= MIN_TOP_AGREEMENT for a in agreement.values())
    verdict = {
        "median_plan_s": median_s,
        "mean_top_agreement": agreement,
        "agree": ok,
        "tolerances": {
            "position_mm": POSITION_TOL_MM,
            "axis_deg": AXIS_TOL_DEG,
            "min_top_agreement": MIN_TOP_AGREEMENT,
        },
    }
    print(json.dumps(verdict))
    if args.out is not None:
        report = {"machine": info, "devices": devices, "rows": rows, "verdict": verdict}
        args.out.write_text(json.dumps(report, indent=1))
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
