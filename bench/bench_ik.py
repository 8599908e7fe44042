"""Time the arm's IK over the workspace: top-down grasps on a grid (two heights, random yaw) and
side grasps (horizontal, radial approach) at three heights; success rate, restarts used, time
per solve (it was part 1 of ``bench_trial.py``). One thread (BLAS and OpenMP pinned to one).

    .venv/bin/python bench/bench_ik.py
"""

from __future__ import annotations

import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402


def bench_ik(seed: int = 0) -> None:
    from hsqbench.sim.ik import ArmIK, IKConfig, Pose
    from hsqbench.sim.robot import Panda
    from hsqbench.sim.scene import build_scene
    from hsqbench.sim.trial import load_trial_config

    model, data, info = build_scene("isolated", "proc_box", seed=0)
    panda = Panda(model, info.robot_prefix)
    cfg: IKConfig = load_trial_config().ik
    ik = ArmIK(model, panda, cfg, [info.table_geom_id, *info.bin_geom_ids])
    ik.sync(data, panda.max_width())
    rng = np.random.default_rng(seed)
    lo, hi = info.workspace_min, info.workspace_max
    down = np.diag([1.0, -1.0, -1.0])
    targets: list[tuple[str, Pose]] = []
    for x in np.linspace(lo[0], hi[0], 5):
        for y in np.linspace(lo[1], hi[1], 5):
            for z in (0.03, 0.15):
                a = rng.uniform(-np.pi / 2, np.pi / 2)
                rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
                targets.append(("top-down", Pose([x, y, z], rz @ down)))
            az = np.arctan2(y, x)
            approach = np.array([np.cos(az), np.sin(az), 0.0])
            closing = np.array([-np.sin(az), np.cos(az), 0.0])
            r = np.column_stack([closing, np.cross(approach, closing), approach])
            for z in (0.05, 0.1, 0.2):
                targets.append(("side", Pose([x, y, z], r)))
    stats: dict[str, list] = {"top-down": [], "side": []}
    for kind, target in targets:
        t0 = time.perf_counter()
        # A grasp or its twin turned by pi about the approach axis, as the trial runner tries.
        for pose in (target, target.flipped()):
            sol = ik.solve(pose, panda.home_arm_q, rng, closest_to=panda.home_arm_q)
            if sol.ok:
                break
        stats[kind].append((sol.ok, sol.restarts, time.perf_counter() - t0, sol.reason))
    print("IK over the workspace (grasp or its twin; closest-to-home selection):")
    for kind, rows in stats.items():
        ok = [r for r in rows if r[0]]
        print(
            f"  {kind:9s}: {len(ok)}/{len(rows)} reachable, "
            f"{np.median([r[2] for r in rows]) * 1000:.0f} ms median per target"
        )
        for r in rows:
            if not r[0]:
                print(f"      unreachable: {r[3]}")
    first_hit = []
    for _, target in targets:
        sol = ik.solve(target, panda.home_arm_q, rng)
        if sol.ok:
            first_hit.append(sol.restarts)
    counts = np.bincount(first_hit, minlength=cfg.restarts + 1)[1:]
    print(f"  restarts needed for a first solution (1..{cfg.restarts}): {counts.tolist()}")


if __name__ == "__main__":
    bench_ik()
