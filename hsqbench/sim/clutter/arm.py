"""The bridge's first step: VGN/GIGA's round with the harness's arm instead of their free hand.

Everything but the executor stays theirs: the scene is generated in their world
(:mod:`hsqbench.sim.clutter.scenes`, the same objects, scales and poses as the hand's round of the
same seed), then moved, at rest, into the harness's scene with the Panda, with their workspace
cube's corner at ``arm_cube_xy_m`` on the table (the cube centred on the harness's workspace);
their camera(s) and depth noise move with it, and their round rule, crop and workspace test
apply. Each grasp goes through the harness's arm: its motion planning (IK over the planner's
grasps in order, ``max_ranks`` of them; none reachable is ``unreachable``) and its execution and
judge (:func:`hsqbench.sim.trial.execution.execute_grasp`: 10 cm pre-grasp, approach stopped and
failed by a push, 70 N close, the lift over the bin's height), ending after the lift: an object
still held is a success, taken out of the world, and the arm goes home.

The bridge's next steps are switches of ``clutter``: ``arm_sensing: harness`` puts the trial
config's own two depth cameras and their noise and calibration error in place of their camera
(their crop kept), and ``arm_until: release`` runs the execution to its end (the carry to the
bin and the release; success is the harness's, the object at rest in the bin).
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import mujoco
import numpy as np

from hsqbench.sim.clutter.step import RoundTally, plan_step, round_streams
from hsqbench.sim.clutter.world import CAMERA_PREFIX, ClutterWorld, add_cameras, outside_cube
from hsqbench.sim.motion import SimUnstable
from hsqbench.sim.outcome import Attempt, Outcome
from hsqbench.sim.recorded_pose import pose7
from hsqbench.sim.recorder import NullRecorder
from hsqbench.sim.scene.info import DepthCamera
from hsqbench.sim.scene.settled import compile_settled
from hsqbench.sim.scene.world import compose_posed, describe_scene


def cube_origin(world: ClutterWorld, table_top_z: float) -> np.ndarray:
    """Their frame's origin in the arm's world."""
    xy = world.config.arm_cube_xy_m
    return np.array([xy[0], xy[1], table_top_z - world.config.scene.table_height_m])


def _arm_spec(world: ClutterWorld, config: Any, origin: np.ndarray, names: list[str]) -> Any:
    """The harness's scene spec with the objects in play at their poses moved by ``origin`` and
    their camera(s) moved with them."""
    clutter = world.config
    poses = []
    for n in names:
        pose = world.pose(n)
        pose[:3] += origin
        poses.append(pose)
    scales = [world.scales[n] for n in names]
    assets = [world.assets[n] for n in names]
    spec = compose_posed(assets, poses, config.scene, config.robot, config.physics, scales)
    add_cameras(spec.worldbody, clutter.camera, clutter.scene.size_m, origin)
    return spec


def arm_env(world: ClutterWorld, kind: str, seed: int, config: Any) -> tuple[Any, np.ndarray]:
    """A :class:`~hsqbench.sim.trial.env.TrialEnv` of the harness's scene with the world's
    objects in play at their poses (shifted into the arm's frame) and their camera(s); returns
    it with their frame's origin in the arm's world."""
    from hsqbench.sim.scene import load_world
    from hsqbench.sim.trial.env import TrialEnv

    clutter = world.config
    names = [n for n in world.objects if n in world.in_play]
    table = load_world(config.scene, config.physics).compile().geom("table")
    origin = cube_origin(world, float(table.pos[2] + table.size[2]))
    built = compile_settled(_arm_spec(world, config, origin, names), names, config.robot,
                            config.physics)  # fmt: skip
    info = describe_scene(built.model, built.data, config.scene, config.robot, kind, seed, names,
                          built.bodies, built.body_ids, built.panda)  # fmt: skip
    theirs = clutter.arm_sensing == "theirs"
    if theirs:
        cam = clutter.camera
        info.depth_cameras = tuple(
            DepthCamera(
                name, cam.width_px, cam.height_px, cam.fovy_deg, cam.min_range_m, cam.max_range_m
            )
            for name in (built.model.camera(i).name for i in range(built.model.ncam))
            if name.startswith(CAMERA_PREFIX)
        )
    lo, hi = world.crop_box()
    info.workspace_min, info.workspace_max = origin + lo, origin + hi
    perception = clutter.perception if theirs else config.perception
    env_config = dataclasses.replace(config, perception=perception, graspability=None)
    assets = {n: world.assets[n] for n in names}
    env = TrialEnv(built.model, built.data, info, assets, env_config, seed, NullRecorder())
    return env, origin


def _outside(env: Any, name: str, origin: np.ndarray, size_m: float) -> bool:
    """Their workspace test in the arm's world (centre of mass outside the cube)."""
    return outside_cube(env.data.xipos[env.info.object_body_ids[name]] - origin, size_m)


def _remove_and_wait(env: Any, origin: np.ndarray, world: ClutterWorld) -> list[str]:
    """Their ``remove_and_wait`` on the arm's scene."""
    sc = world.config.scene
    out: list[str] = []
    while True:
        env.stepper.hold(sc.rest_timeout_s)
        live = [n for n in env.info.objects if n not in env.removed]
        gone = [n for n in live if _outside(env, n, origin, sc.size_m)]
        if not gone:
            return out
        for n in gone:
            env.remove(n)
        out += gone


def run_arm_round(world: ClutterWorld, kind: str, seed: int, planner: Any, config: Any) -> Any:
    """The round of :func:`hsqbench.sim.clutter.round.run_hand_round` with the arm (module
    notes); ``world`` is the generated scene of their world."""
    from hsqbench.sim.trial.attempt import resolve_planner
    from hsqbench.sim.trial.release import return_home

    plan_with = resolve_planner(planner, config)
    presented = [n for n in world.objects if n in world.in_play]
    env, origin = arm_env(world, kind, seed, config)
    rngs = round_streams(seed)
    env.rngs.update({n: rngs[n] for n in ("perception_calibration", "perception_noise")})
    tally = RoundTally()
    rule = world.config.rule
    with env:
        while rule.stop_reason(tally.outcomes, bool(env.objects_on_table())) is None:
            attempt = _arm_attempt(env, plan_with, kind, config, rngs)
            tally.record(attempt)
            if attempt.outcome in (Outcome.NO_GRASP_FOUND, Outcome.SIM_UNSTABLE):
                continue
            if attempt.outcome == Outcome.SUCCESS:
                env.remove(attempt.target)  # taken out of the hand before it opens
            try:
                return_home(env)
                gone = _remove_and_wait(env, origin, world)
            except SimUnstable as exc:
                attempt.detail += f"; then the simulation became unstable: {exc}"
                break
            tally.lose(attempt, gone)
    return tally.result(presented, [n for n in world.objects if n not in presented], seed, planner)


def _arm_attempt(env: Any, planner: Any, kind: str, config: Any, rngs: dict) -> Attempt:
    """Look, plan (:func:`~hsqbench.sim.clutter.step.plan_step`), motion-plan and execute one
    grasp with the arm."""
    t0 = time.perf_counter()
    try:
        look = env.look()
    except SimUnstable as exc:
        return Attempt(Outcome.SIM_UNSTABLE, detail=str(exc))
    planned = plan_step(
        look.obs,
        time.perf_counter() - t0,
        planner,
        kind,
        config,
        int(rngs["planner"].integers(2**31)),
        env.info.support_plane,
        lambda: look.truth,
    )
    if planned.ended is not None:
        return planned.ended
    return _arm_execute(env, planned.grasps, planned.points, planned.common, config)


def _arm_execute(env: Any, grasps: Any, points: Any, common: dict, config: Any) -> Attempt:
    """Motion-plan the grasps in order and execute the first reachable one with the arm, up to
    ``clutter.arm_until``."""
    from hsqbench.sim.trial.attempt import AttemptTrace, grasp_fields, plan_motions
    from hsqbench.sim.trial.execution import execute_grasp

    trace = AttemptTrace()
    t0 = time.perf_counter()
    chosen = plan_motions(env, grasps, points, trace)
    if chosen.motion is None:
        top = grasps[0]
        return Attempt(
            Outcome.UNREACHABLE,
            target=env.probe.nearest_object(env.data, np.asarray(top.position)),
            score=float(top.score),
            width_m=float(top.width),
            grasp_pose=pose7(top.position, top.rotation),
            ranks_tried=trace.ranks_tried,
            execution_s=time.perf_counter() - t0,
            detail=chosen.reasons[0] if chosen.reasons else "no reachable grasp",
            **common,
        )
    grasp, motion = grasps[chosen.rank], chosen.motion
    intended = env.probe.nearest_object(env.data, np.asarray(grasp.position))
    env.panda.open_gripper(env.data)
    mujoco.mj_forward(env.model, env.data)
    try:
        res = execute_grasp(env, motion, intended, until=config.clutter.arm_until)
        outcome, target, detail = res.outcome, res.target, res.detail
        sim_time = res.sim_time_s
    except SimUnstable as exc:
        outcome, target, detail, sim_time = Outcome.SIM_UNSTABLE, intended, str(exc), 0.0
    return Attempt(
        outcome,
        target=target,
        **grasp_fields(grasp, chosen.rank),
        execution_s=time.perf_counter() - t0,
        grasp_pose=pose7(motion.grasp_pose.position, motion.grasp_pose.rotation),
        grasp_flipped=motion.flipped,
        sim_time_s=sim_time,
        ranks_tried=trace.ranks_tried,
        detail=detail,
        **common,
    )
