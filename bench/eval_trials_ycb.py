"""Isolated grasp trials (``hsqbench.sim.trial.run_isolated_trial``) on the 15 YCB objects.

One trial per object and seed with the hsq planner (``--planner-config`` selects a planner YAML,
e.g. one with the additions switched off), then per object: successes / trials and the
outcomes, and a total. ``--json`` keeps every attempt (outcome, detail, score, width, times).

    .venv/bin/python bench/eval_trials_ycb.py [--seeds 0 1 2] [--objects mug banana]
        [--planner-config configs/planner.yaml] [--trial-config configs/trial.yaml] [--json out.json]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections import Counter  # noqa: E402
from dataclasses import asdict  # noqa: E402
from pathlib import Path  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main() -> int:
    from hsqbench.assets.library import ycb_names
    from hsqbench.planner.hsq.planner import HSQPlanner
    from hsqbench.sim.trial import load_trial_config, run_isolated_trial

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--objects", nargs="*", default=None, help="default: the 15 YCB objects")
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--planner-config", default=None, help="planner YAML (default: planner)")
    parser.add_argument("--trial-config", default=None, help="trial YAML (default: trial)")
    parser.add_argument("--json", default=None, help="write every attempt here")
    args = parser.parse_args()

    planner = HSQPlanner(args.planner_config)
    config = load_trial_config("trial" if args.trial_config is None else args.trial_config)
    names = args.objects or ycb_names()
    rows = []
    for name in names:
        for seed in args.seeds:
            start = time.perf_counter()
            result = run_isolated_trial(name, seed, planner, config)
            attempt = result.attempts[0]
            rows.append({"object": name, "seed": seed, **asdict(attempt)})
            print(
                f"{name:22s} s{seed} {attempt.outcome!s:22s} grasps={attempt.n_grasps:4d} "
                f"rank={attempt.rank_executed:2d} score={attempt.score:.3f} "
                f"w={attempt.width_m * 1000:5.1f}mm plan={attempt.planning_s:.2f}s "
                f"({time.perf_counter() - start:.0f}s) {attempt.detail[:140]}",
                flush=True,
            )
    print("per object:")
    for name in names:
        mine = [r for r in rows if r["object"] == name]
        ok = sum(r["outcome"] == "success" for r in mine)
        outcomes = Counter(str(r["outcome"]) for r in mine)
        print(f"  {name:22s} {ok}/{len(mine)}  {dict(outcomes)}")
    total = Counter(str(r["outcome"]) for r in rows)
    ok = total.get("success", 0)
    print(f"SUMMARY success {ok}/{len(rows)} ({ok / len(rows):.0%}); outcomes {dict(total)}")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
