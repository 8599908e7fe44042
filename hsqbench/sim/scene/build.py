"""Building a scene: objects drawn and placed by seed, composed, settled and described."""

from __future__ import annotations

import time
from collections.abc import Sequence

import mujoco
import numpy as np

from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.physics import PhysicsConfig, load_physics_config
from hsqbench.sim.robot import RobotConfig, load_robot_config
from hsqbench.sim.scene.config import SceneConfig, load_scene_config
from hsqbench.sim.scene.info import SceneInfo
from hsqbench.sim.scene.pile_scene import settled_pile
from hsqbench.sim.scene.placement import (
    draw_rests,
    layout_objects,
    resolve_scene_objects,
    scene_object_count,
)
from hsqbench.sim.scene.settled import compile_settled
from hsqbench.sim.scene.world import compose_scene, describe_scene


def build_scene(
    kind: str,
    objects: Sequence[str | ObjectLike] | str | ObjectLike | None = None,
    seed: int = 0,
    *,
    scene_config: SceneConfig | None = None,
    robot_config: RobotConfig | None = None,
    physics_config: PhysicsConfig | None = None,
) -> tuple[mujoco.MjModel, mujoco.MjData, SceneInfo]:
    """Build, settle and describe a scene (:func:`build_scene_spec` without the spec)."""
    return build_scene_spec(
        kind,
        objects,
        seed,
        scene_config=scene_config,
        robot_config=robot_config,
        physics_config=physics_config,
    )[1:]


def build_scene_spec(
    kind: str,
    objects: Sequence[str | ObjectLike] | str | ObjectLike | None = None,
    seed: int = 0,
    *,
    scene_config: SceneConfig | None = None,
    robot_config: RobotConfig | None = None,
    physics_config: PhysicsConfig | None = None,
) -> tuple[mujoco.MjSpec, mujoco.MjModel, mujoco.MjData, SceneInfo]:
    """Build, settle and describe a scene; also returns the spec it was compiled from.

    Args:
        kind: ``"isolated"``, ``"packed"`` or ``"pile"`` (:mod:`hsqbench.sim.scene.pile`).
        objects: object names (library) or objects; ``None`` draws by seed from the 15 YCB
            objects (one for isolated, ``n_packed`` different ones for packed,
            ``pile.n_objects`` for a pile).
        seed: the only source of randomness; the same seed gives the same scene.

    Returns:
        ``(spec, model, data, info)`` with ``data`` at the settled state (also keyframe
        ``initial``, in the model only: the spec's keyframe is empty).

    Raises:
        ValueError: unknown kind or object (the library lists the known names), duplicate
            objects, or a layout that cannot be placed (:class:`PlacementError`; a pile that
            does not settle on the table: :class:`PileError`).
    """
    t0 = time.perf_counter()
    cfg = scene_config or load_scene_config()
    robot = robot_config or load_robot_config()
    physics = physics_config or load_physics_config()
    rng = np.random.default_rng(seed)
    assets = resolve_scene_objects(kind, objects, scene_object_count(kind, cfg), rng)
    names = [a.name for a in assets]
    rests, rejected = None, []
    if kind == "pile":
        built, rejected = settled_pile(assets, seed, cfg, robot, physics, rng)
    else:
        rests = draw_rests(assets, cfg.placement, rng)
        poses = layout_objects(assets, cfg, rng, rests)
        spec = compose_scene(assets, poses, cfg, robot, physics, rests)
        built = compile_settled(spec, names, robot, physics)
    model, data = built.model, built.data
    info = describe_scene(
        model, data, cfg, robot, kind, seed, names, built.bodies, built.body_ids, built.panda
    )
    info.settle_time_s, info.max_speed_after_settle = built.settle_time_s, built.max_speed
    info.resting_poses = {
        a.name: (-1 if rests is None else int(rests[i][0])) for i, a in enumerate(assets)
    }
    info.rejected_drops = list(rejected)
    info.reset(model, data)
    info.build_time_s = time.perf_counter() - t0
    return built.spec, model, data, info
