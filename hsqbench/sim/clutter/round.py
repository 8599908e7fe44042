"""One clutter-removal round as VGN/GIGA run theirs (``src/vgn/experiments/clutter_removal.py``,
``run``): look, plan, execute the planner's best grasp with the free hand, until the stop rule.

Each step: the camera(s) render depth with their noise (``clutter.perception``); the fused cloud
(cropped to the workspace, the table removed) and the depth images go to the planner with the
table plane and the workspace; the planner's first grasp is executed
(:mod:`hsqbench.sim.clutter.execution`: no fall-back to later grasps, as theirs); a held object
is taken out (cleared), the world comes to rest and objects outside the workspace are taken out
(not cleared). The round ends (``clutter.rule``, :mod:`hsqbench.sim.stop_rule`) when no object
is left, after two consecutive failures, or at the first step without a grasp (theirs: an
empty cloud or no detection), which is recorded as a ``no_grasp_found`` attempt; a planner that
raises or breaks its contract is a ``planner_error`` attempt, which ends the round the same way.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from hsqbench.sim.clutter.execution import execute_hand_grasp
from hsqbench.sim.clutter.step import RoundTally, plan_step, round_streams
from hsqbench.sim.clutter.world import ClutterWorld
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult
from hsqbench.sim.recorded_pose import pose7
from hsqbench.sim.trial.attempt import grasp_fields


def _perception(world: ClutterWorld, rng: np.random.Generator) -> Any:
    from hsqbench.sim.perception import Perception

    lo, hi = world.crop_box()
    return Perception(
        world.model,
        world.cameras,
        support_plane=world.support_plane,
        workspace_min=lo,
        workspace_max=hi,
        rng=rng,
        config=world.config.perception,
    )


def _truth(world: ClutterWorld, rng: np.random.Generator) -> Any:
    from hsqbench.sim.scene_truth import scene_truth

    seed = int(rng.integers(2**31))
    return scene_truth(
        world.model, world.data, world.geom_ids, list(world.in_play), world.support_plane, seed
    )


def run_hand_round(
    world: ClutterWorld, kind: str, seed: int, planner: Any, config: Any
) -> RoundResult:
    """The round on the generated ``world`` with the free hand (module notes); ``planner`` a
    name or a planner, ``config`` the trial config (its planners, ``min_cloud_points`` and
    ``recorded_scores`` apply)."""
    from hsqbench.sim.trial.attempt import resolve_planner

    clutter = world.config
    plan_with = resolve_planner(planner, config)
    presented = [n for n in world.objects if n in world.in_play]
    rngs = round_streams(seed)
    perception = _perception(world, rngs["perception_calibration"])
    tally = RoundTally()
    try:
        while clutter.rule.stop_reason(tally.outcomes, bool(world.in_play)) is None:
            attempt = _attempt(world, perception, plan_with, rngs, kind, config)
            tally.record(attempt)
            if attempt.outcome not in (Outcome.NO_GRASP_FOUND,):
                tally.lose(attempt, world.remove_and_wait())
    finally:
        perception.close()
    return tally.result(presented, [n for n in world.objects if n not in presented], seed, planner)


def _attempt(
    world: ClutterWorld,
    perception: Any,
    planner: Any,
    rngs: dict[str, np.random.Generator],
    kind: str,
    config: Any,
) -> Attempt:
    t0 = time.perf_counter()
    obs = perception.observe(world.data, rngs["perception_noise"])
    planned = plan_step(
        obs,
        time.perf_counter() - t0,
        planner,
        kind,
        config,
        int(rngs["planner"].integers(2**31)),
        world.support_plane,
        lambda: _truth(world, rngs["oracle"]),
    )
    if planned.ended is not None:
        return planned.ended
    grasps, common = planned.grasps, planned.common
    grasp = grasps[0]
    position, rotation = np.asarray(grasp.position, float), np.asarray(grasp.rotation, float)
    t2 = time.perf_counter()
    res = execute_hand_grasp(world, position, rotation)
    outcome, detail = res.outcome, res.detail
    if not (np.isfinite(world.data.qpos).all() and np.isfinite(world.data.qvel).all()):
        outcome, detail = Outcome.SIM_UNSTABLE, f"non-finite state after the grasp ({detail})"
    return Attempt(
        outcome,
        target=res.target,
        **grasp_fields(grasp, 0),
        execution_s=time.perf_counter() - t2,
        grasp_pose=pose7(position, rotation),
        sim_time_s=res.sim_time_s,
        ranks_tried=1,
        detail=detail,
        **common,
    )
