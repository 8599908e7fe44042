"""Time and score the trial runner: IK over the workspace, then isolated trials end to end.

Part 1, IK: top-down grasps on a grid over the workspace (two heights, random yaw) and side grasps
(horizontal, radial approach) at three heights; success rate, restarts used, time per solve.

Part 2, trials: ``run_isolated_trial`` for each object and seed with the paper's planner; success
rate and outcomes, the median wall time per trial, and where it goes (scene build, perception,
planning, IK, simulation) plus the simulated seconds per motion phase. One process, one thread
(BLAS and OpenMP pinned to one thread before numpy loads). Assets must be built
(``make assets``); the first trial of the process also pays for imports and the GL context.

    .venv/bin/python bench/bench_trial.py [--objects proc_box proc_cylinder] [--seeds 5]
        [--sensor cameras|surface] [--ycb] [--skip-ik]
"""

from __future__ import annotations

import argparse
import os
import time

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

YCB_SAMPLE = ["cracker_box", "tomato_soup_can", "mustard_bottle", "foam_brick", "power_drill"]


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


def bench_trials(objects: list[str], seeds: int, sensor: str) -> None:
    from dataclasses import replace

    from hsqbench.sim.trial import load_trial_config, run_isolated_trial

    cfg = replace(load_trial_config(), sensor=sensor)
    rows = []
    print(f"\nIsolated trials ({sensor} sensor, planner hsq):")
    print(
        f"{'object':22s} {'seed':>4s} {'outcome':22s} {'rank':>4s} {'wall_s':>6s} {'build':>6s} "
        f"{'perc':>6s} {'plan':>6s} {'ik':>6s} {'sim':>6s} {'sim_t':>6s}"
    )
    for obj in objects:
        for seed in range(seeds):
            traces: list = []
            t0 = time.perf_counter()
            result = run_isolated_trial(obj, seed, "hsq", cfg, traces=traces)
            wall = time.perf_counter() - t0
            a, tr = result.attempts[0], traces[0]
            rows.append((obj, a, tr, wall))
            print(
                f"{obj:22s} {seed:4d} {a.outcome!s:22s} {a.rank_executed:4d} {wall:6.2f} "
                f"{tr.scene_build_s:6.2f} {a.perception_s:6.2f} {a.planning_s:6.2f} "
                f"{tr.ik_s:6.2f} {tr.sim_s:6.2f} {tr.sim_time_s:6.1f}",
                flush=True,
            )
    walls = np.array([r[3] for r in rows])
    ok = sum(r[1].success for r in rows)
    print(f"success {ok}/{len(rows)}; outcomes:", end="")
    outcomes: dict[str, int] = {}
    for r in rows:
        outcomes[str(r[1].outcome)] = outcomes.get(str(r[1].outcome), 0) + 1
    print(" " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())))
    later = walls[1:] if len(walls) > 1 else walls
    print(
        f"wall per trial: median {np.median(walls):.2f} s (without the process's first trial: "
        f"{np.median(later):.2f} s), max {walls.max():.2f} s"
    )

    def med(values) -> float:
        return float(np.median(values)) if len(values) else float("nan")

    executed = [r for r in rows if r[2].sim_time_s > 0]
    print(
        "median phase wall times: "
        f"build {med([r[2].scene_build_s for r in rows]):.2f} s, "
        f"perception {med([r[1].perception_s for r in rows]):.2f} s, "
        f"planning {med([r[1].planning_s for r in rows]):.2f} s, "
        f"IK {med([r[2].ik_s for r in rows]):.2f} s, "
        f"simulation {med([r[2].sim_s for r in executed]):.2f} s "
        f"({med([r[2].sim_time_s for r in executed]):.1f} s simulated, "
        f"{med([r[2].sim_s / r[2].sim_time_s for r in executed]) * 1000:.0f} ms wall per "
        "simulated second)"
    )
    phases: dict[str, list[float]] = {}
    for r in executed:
        for k, v in r[2].phases.items():
            phases.setdefault(k, []).append(v)
    print(
        "median simulated seconds per phase: "
        + ", ".join(f"{k} {med(v):.2f}" for k, v in phases.items())
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", nargs="+", default=["proc_box", "proc_cylinder"])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--sensor", choices=("cameras", "surface"), default="cameras")
    parser.add_argument("--ycb", action="store_true", help=f"add {', '.join(YCB_SAMPLE)}")
    parser.add_argument("--skip-ik", action="store_true")
    args = parser.parse_args()
    objects = list(args.objects) + (YCB_SAMPLE if args.ycb else [])
    if not args.skip_ik:
        bench_ik()
    bench_trials(objects, args.seeds, args.sensor)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
