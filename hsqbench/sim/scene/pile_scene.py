"""A pile as a benchmark scene: the drop's poses in the ordinary scene (with the robot), checked
there too, remembered per process, and the cheap check the experiment runner asks in the parent."""

from __future__ import annotations

import os
from collections.abc import Sequence

import numpy as np

from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.robot import RobotConfig
from hsqbench.sim.scene.config import SceneConfig
from hsqbench.sim.scene.footprint import hull_vertices
from hsqbench.sim.scene.pile import PileDrop, PileError, drop_pile, heap_problem
from hsqbench.sim.scene.settled import Settled, compile_settled
from hsqbench.sim.scene.world import compose_posed

# Piles already made in this process, by objects (and their hull files' times), seed and
# configs: the parent's draw check (:func:`pile_placeable`) and, with one worker, every planner's
# round of the same pile reuse one drop (seconds of simulation) instead of repeating it.
_CACHE: dict[tuple, PileDrop | PileError] = {}
_CACHE_SIZE = 64


def _cache_key(assets, seed, *configs) -> tuple | None:
    try:
        files = tuple(
            (a.name, tuple((str(p), os.stat(p).st_mtime_ns) for p in a.collision_meshes))
            for a in assets
        )
        key = (files, seed, *configs)
        hash(key)
    except (TypeError, OSError):  # objects not from files, or a config that cannot be hashed
        return None
    return key


def _final(
    assets: Sequence[ObjectLike],
    poses: list[np.ndarray],
    cfg: SceneConfig,
    robot: RobotConfig,
    physics: PhysicsConfig,
) -> tuple[Settled, str | None]:
    """The ordinary scene with the objects at ``poses``, settled, and why it is no pile."""
    names = [a.name for a in assets]
    built = compile_settled(
        compose_posed(assets, poses, cfg, robot, physics), names, robot, physics
    )
    m, d = built.model, built.data
    vertices = []
    for a in assets:
        b = built.body_ids[a.name]
        vertices.append(hull_vertices(a) @ d.xmat[b].reshape(3, 3).T + d.xpos[b])
    table = m.geom("table").id
    top_z = float(m.geom_pos[table, 2] + m.geom_size[table, 2])
    why = heap_problem(names, vertices, built.max_speed, top_z, cfg, physics)
    return built, None if why is None else f"in the scene with the robot, {why}"


def settled_pile(
    assets: Sequence[ObjectLike],
    seed: int,
    cfg: SceneConfig,
    robot: RobotConfig,
    physics: PhysicsConfig,
    rng: np.random.Generator,
) -> tuple[Settled, list[str]]:
    """The pile scene of ``assets`` and the reasons of the drops rejected before it.

    ``rng`` must be the scene seed's generator after the object draw (as :func:`build_scene`
    makes it): a pile remembered for the same objects, seed and configs is then the one this
    would drop, and is only composed again (deterministic: the same scene).

    Raises:
        PileError: no drop gave a pile at rest on the table in the workspace.
    """
    kept: dict[str, Settled] = {}

    def accept(poses: list[np.ndarray]) -> str | None:
        built, why = _final(assets, poses, cfg, robot, physics)
        if why is None:
            kept["scene"] = built
        return why

    key = _cache_key(assets, seed, cfg, robot, physics)
    if key is None or key not in _CACHE:
        try:
            pile: PileDrop | PileError = drop_pile(assets, cfg, physics, rng, accept)
        except PileError as exc:
            pile = exc
        if key is not None:
            _CACHE[key] = pile
            while len(_CACHE) > _CACHE_SIZE:
                _CACHE.pop(next(iter(_CACHE)))
    else:
        pile = _CACHE[key]
    if isinstance(pile, PileError):
        raise PileError(str(pile))
    if "scene" not in kept:
        kept["scene"] = _final(assets, [p.copy() for p in pile.poses], cfg, robot, physics)[0]
    return kept["scene"], list(pile.rejected)


def pile_placeable(
    objects: Sequence[str | ObjectLike],
    seed: int,
    scene_config: SceneConfig | None = None,
    physics_config: PhysicsConfig | None = None,
    robot_config: RobotConfig | None = None,
) -> bool:
    """Whether ``build_scene("pile", objects, seed)`` gets a pile at rest on the table.

    Exact: the scene builder's own seeded drops and checks (about a second or two per pile;
    remembered, so the round's trials in this process reuse it). Unknown or duplicate objects
    still raise ``ValueError``.
    """
    from hsqbench.sim.physics import load_physics_config
    from hsqbench.sim.robot import load_robot_config
    from hsqbench.sim.scene.config import load_scene_config
    from hsqbench.sim.scene.placement import resolve_scene_objects

    cfg = scene_config or load_scene_config()
    rng = np.random.default_rng(seed)
    assets = resolve_scene_objects("pile", objects, cfg.pile.n_objects, rng)
    try:
        settled_pile(
            assets,
            seed,
            cfg,
            robot_config or load_robot_config(),
            physics_config or load_physics_config(),
            rng,
        )
    except PileError:
        return False
    return True
