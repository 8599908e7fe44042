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
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hsqbench.planner.failure import PlannerError, checked_plan
from hsqbench.sim.clutter.execution import execute_hand_grasp
from hsqbench.sim.clutter.scenes import build_clutter_scene
from hsqbench.sim.clutter.world import ClutterWorld
from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult
from hsqbench.sim.recorded_pose import pose7

#: Independent random streams drawn from a round's seed (the scene has the seed itself).
STREAMS = ("perception_calibration", "perception_noise", "planner", "oracle")


def _perception(world: ClutterWorld, rng: np.random.Generator) -> Any:
    from hsqbench.sim.perception import Perception

    sc = world.config.scene
    # Their cloud's crop (``place_table``): 2 cm inside the cube's sides, up to its top; the
    # table goes by perception's table margin.
    lo = np.array([0.02, 0.02, sc.table_height_m])
    hi = np.array([sc.size_m - 0.02, sc.size_m - 0.02, sc.size_m])
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


def run_clutter_round(
    objects: Sequence[str | ObjectLike],
    seed: int,
    planner: Any,
    config: Any,
    kind: str = "packed",
) -> RoundResult:
    """A round of VGN/GIGA's clutter removal with ``planner`` (a name or a planner) under the
    trial config ``config`` whose ``clutter`` is set (its robot hand, physics, planners,
    ``min_cloud_points`` and ``recorded_scores`` apply)."""
    from hsqbench.sim.trial.attempt import resolve_planner

    clutter = config.clutter
    if clutter is None:
        raise ValueError("run_clutter_round needs a trial config with clutter: set")
    plan_with = resolve_planner(planner, config)
    name = planner if isinstance(planner, str) else str(getattr(planner, "name", planner))
    world = build_clutter_scene(kind, objects, seed, clutter, config.robot, config.physics)
    if clutter.executor == "arm":
        from hsqbench.sim.clutter.arm import run_arm_round

        return run_arm_round(world, kind, seed, planner, config)
    presented = [n for n in world.objects if n in world.in_play]
    streams = np.random.SeedSequence([seed, 1]).spawn(len(STREAMS))
    rngs = {n: np.random.default_rng(s) for n, s in zip(STREAMS, streams, strict=True)}
    perception = _perception(world, rngs["perception_calibration"])
    attempts: list[Attempt] = []
    cleared: list[str] = []
    lost: list[str] = []
    outcomes: list[str] = []
    try:
        while clutter.rule.stop_reason(outcomes, bool(world.in_play)) is None:
            attempt = _attempt(world, perception, plan_with, rngs, kind, config)
            attempts.append(attempt)
            outcomes.append(attempt.outcome.value)
            if attempt.outcome == Outcome.SUCCESS:
                cleared.append(attempt.target)
            if attempt.outcome not in (Outcome.NO_GRASP_FOUND,):
                gone = world.remove_and_wait()
                lost += gone
                for n in gone:
                    attempt.detail += f"; {n} left the workspace (taken out, not cleared)"
    finally:
        perception.close()
    return RoundResult(
        objects=presented,
        seed=seed,
        planner=name,
        attempts=attempts,
        objects_cleared=cleared,
        objects_graspable=None,
        objects_lost=lost,
        scene_settle_s=float("nan"),
        scene_max_speed=float("nan"),
        objects_unplaced=[n for n in world.objects if n not in presented],
    )


@dataclass
class Planned:
    """A look and a plan: ``ended`` when the step ends without a grasp (too few points, no
    grasp, the planner's own error), else the planner's ``grasps`` and what every attempt
    records (``common``)."""

    ended: Attempt | None
    grasps: Sequence[Any] = ()
    points: Any = None
    common: dict[str, Any] = field(default_factory=dict)


def plan_step(
    obs: Any,
    perception_s: float,
    planner: Any,
    kind: str,
    config: Any,
    seed: int,
    support_plane: Any,
    truth: Callable[[], Any],
) -> Planned:
    """Plan on one observation as their loop does (the cloud, the depth images, the table plane
    and the workspace; ``truth`` is called for a privileged planner only)."""
    from hsqbench.planner.api import PlanningContext

    points = np.asarray(obs.points)
    privileged = getattr(planner, "privileged", False)
    if len(points) < config.min_cloud_points and not privileged:
        detail = f"the cloud has {len(points)} points (fewer than {config.min_cloud_points})"
        return Planned(Attempt(Outcome.NO_GRASP_FOUND, perception_s=perception_s, detail=detail))
    context = PlanningContext(
        support_plane=tuple(float(x) for x in support_plane),
        packed=True,
        seed=seed,
        camera_positions=np.asarray(obs.camera_positions),
        workspace_bounds=(obs.workspace_min, obs.workspace_max),
        truth=truth() if privileged else None,
        scene=kind,
        depth_views=getattr(obs, "cameras", None),
    )
    t1 = time.perf_counter()
    try:
        plan = checked_plan(planner, points, context)
    except PlannerError as exc:  # the planner's own failure: a failed attempt without a grasp
        planning_s = time.perf_counter() - t1
        return Planned(
            Attempt(
                Outcome.PLANNER_ERROR,
                perception_s=perception_s,
                planning_s=planning_s,
                detail=str(exc),
            )
        )
    planning_s = time.perf_counter() - t1
    grasps = plan.grasps
    n_top = min(len(grasps), config.recorded_scores)
    common = {
        "n_grasps": len(grasps),
        "perception_s": perception_s,
        "planning_s": planning_s,
        "top_scores": tuple(float(grasps[i].score) for i in range(n_top)),
        "planner_stages_s": {k: float(v) for k, v in plan.timings.items()},
    }
    if not len(grasps):
        detail = plan.reason or "the planner returned no grasp"
        return Planned(Attempt(Outcome.NO_GRASP_FOUND, detail=detail, **common))
    return Planned(None, grasps, points, common)


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
        rank_executed=0,
        score=float(grasp.score),
        factors={k: float(v) for k, v in grasp.factors.items()},
        width_m=float(grasp.width),
        execution_s=time.perf_counter() - t2,
        grasp_pose=pose7(position, rotation),
        sim_time_s=res.sim_time_s,
        ranks_tried=1,
        detail=detail,
        **common,
    )
