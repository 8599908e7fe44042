"""Whether the oracle is a ceiling: on how many of the presentations that some planner grasped
does it find a grasp?

A presentation is an isolated trial's settled scene (every planner sees the same one, from
the trial's seed), or a packed or pile round's initial scene (likewise shared). *Grasped*: some
planner of the run succeeded on it (for a round: the objects some planner grasped at any
attempt). *Covered*: the oracle finds a feasible grasp on that object in that scene.

The report reads the verdicts a run recorded (``graspable`` in ``attempts.csv``,
``objects_graspable`` in ``rounds.csv``: the oracle of the run's code;
:func:`hsqbench.experiment.graspable.coverage_from_rows`). :func:`recheck` rebuilds each presentation and runs today's oracle on it (no trial runs): an
isolated scene is the object at its recorded settled pose (``object_pose``), a round's initial
scene is rebuilt from its seed.

    python -m hsqbench.experiment.coverage results/ycb3 [--limit 50]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pandas as pd

from hsqbench.experiment.graspable import Coverage, grasped_presentations
from hsqbench.experiment.results import STATUS_OK
from hsqbench.experiment.rows import pose_table


# ---- recheck with today's oracle -----------------------------------------------------------
def _truths(run_dir: Path, todo: pd.DataFrame) -> Iterator[tuple[tuple, object]]:
    """(key, SceneTruth) per presentation of ``todo`` (experiment, objects, seed, pose)."""
    import mujoco

    from hsqbench.sim.scene_truth import scene_truth
    from hsqbench.sim.trial.env import TrialEnv, trial_rngs
    from hsqbench.viz.episodes import run_trial_config

    config = run_trial_config(run_dir)
    for (exp, objects), group in todo.groupby(["experiment", "objects"], sort=False):
        names = [o for o in objects.split(";") if o]
        if exp != "isolated":
            for seed in group["seed"]:
                with TrialEnv.build(exp, names, int(seed), config) as env:
                    yield (exp, objects, str(seed)), env.truth()
            continue
        # One scene per object; each presentation is that object at its recorded settled pose,
        # with the oracle seed the trial drew (the first draw of its "oracle" stream).
        first = int(group["seed"].iloc[0])
        with TrialEnv.build(exp, names, first, config) as base:
            body = base.info.object_body_ids[names[0]]
            adr = base.model.jnt_qposadr[base.model.body_jntadr[body]]
            data = mujoco.MjData(base.model)
            for seed, pose in zip(group["seed"], pose_table(group["object_pose"]), strict=True):
                data.qpos[:] = base.data.qpos
                data.qpos[adr : adr + 7] = pose
                oracle_seed = int(trial_rngs(int(seed))["oracle"].integers(2**31))
                truth = scene_truth(
                    base.model,
                    data,
                    base.info.object_geom_ids,
                    names,
                    base.info.support_plane,
                    oracle_seed,
                    base.panda,
                )
                yield (exp, objects, str(seed)), truth


def recheck(run_dir: str | Path, limit: int | None = None, log=None) -> Coverage:
    """Coverage of today's oracle (``configs/oracle.yaml``) on the presentations of
    ``run_dir`` that some planner grasped, each rebuilt (module docstring)."""
    from hsqbench.experiment.run_data import load_run
    from hsqbench.planner.oracle import OraclePlanner, feasible_grasps

    run_dir = Path(run_dir)
    attempts = load_run(run_dir).attempts
    grasped = grasped_presentations(attempts)
    ok = attempts[attempts["status"] == STATUS_OK]
    pose = ok[ok["experiment"] == "isolated"].groupby(["objects", "seed"])["object_pose"].first()
    keys = grasped[["experiment", "objects", "seed"]].drop_duplicates()
    if limit is not None:
        keys = keys.head(limit)  # the first ones, a few objects: one scene build each
    keys = keys.assign(
        object_pose=[
            pose.get((o, s), "") if e == "isolated" else ""
            for e, o, s in zip(keys["experiment"], keys["objects"], keys["seed"], strict=True)
        ]
    )
    oracle = OraclePlanner()
    parts: dict[str, list[int]] = {}
    t0 = time.perf_counter()
    for n, (key, truth) in enumerate(_truths(run_dir, keys), 1):
        counts = feasible_grasps(truth, oracle.gripper, oracle.config, truth.seed)
        mine = grasped[
            (grasped["experiment"] == key[0])
            & (grasped["objects"] == key[1])
            & (grasped["seed"].astype(str) == key[2])
        ]
        part = parts.setdefault(key[0], [0, 0])
        for obj in mine["object"]:
            hit = counts.get(obj, 0) > 0
            part[0] += int(hit)
            part[1] += 1
            if log is not None and not hit:
                print(f"not covered: {key[0]} {key[1]} seed {key[2]}: {obj}", file=log)
        if log is not None and n % 10 == 0:
            print(f"{n}/{len(keys)} presentations, {time.perf_counter() - t0:.0f} s", file=log)
    return Coverage(
        sum(c for c, _ in parts.values()),
        sum(g for _, g in parts.values()),
        {e: (c, g) for e, (c, g) in parts.items()},
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="a run folder (results/ycb3)")
    parser.add_argument("--limit", type=int, default=None, help="only the first this many")
    args = parser.parse_args(argv)
    if not (Path(args.run) / "run.json").exists():
        print(f"{args.run} has no run.json: give a benchmark run folder", file=sys.stderr)
        return 2
    from threadpoolctl import threadpool_limits

    t0 = time.process_time()
    with threadpool_limits(1):
        cov = recheck(args.run, args.limit, log=sys.stdout)
    print(cov.line())
    print(f"CPU {time.process_time() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
