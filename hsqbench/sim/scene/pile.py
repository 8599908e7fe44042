"""Pile scenes (VGN, Breyer et al. 2020; GIGA, Jiang et al. 2021): objects dropped one by one
from random orientations into a box over the workspace centre, the box removed, the heap settled.

The drop runs in a model of its own: the static world, four temporary walls and the objects,
without the robot (far from the box, it plays no part while objects fall). Objects not yet dropped are parked away
from everything, weightless (gravity compensation) and without contacts; dropping one gives it
a pose, its weight and its contacts back. After the last drop the walls lose their contacts and
the heap settles again. The settled poses then go into the ordinary scene, with the robot
(:mod:`hsqbench.sim.scene.pile_scene`), which settles and is checked once more; so a pile is a
scene of the same form as a packed one: the trial runner, cameras, judge and recorder need
nothing new.

A drop whose settling does not converge, or whose objects do not all end at rest on the table
inside the workspace (in the drop model or in the final scene), is made again with the next draws of the same generator (the scene
seed's), up to ``pile.max_drop_attempts``; the reasons are kept (:attr:`PileDrop.rejected`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import mujoco
import numpy as np

from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.scene.config import SceneConfig
from hsqbench.sim.scene.footprint import hull_vertices
from hsqbench.sim.scene.info import OBJECT_PREFIX
from hsqbench.sim.scene.placement import PlacementError
from hsqbench.sim.scene.world import compose_posed, settle

WALL_PREFIX = "pile/wall_"
# Objects waiting for their drop: 1 m apart, 3 m behind the robot, 1 m up: far from everything.
_PARK_XYZ = (-3.0, 0.0, 1.0)
_PARK_STEP_M = 1.0
# Tolerance of the on-table test: the lowest hull point may sink this far into the table top
# (soft contacts: a few tenths of a millimetre under a heap).
_SINK_TOLERANCE_M = 0.005
# Gap kept between a dropped object's bounding box and the walls at the drop.
_WALL_GAP_M = 0.002


class PileError(PlacementError):
    """No drop of the pile settled with every object at rest on the table in the workspace."""


@dataclass
class PileDrop:
    """A settled pile: each object's pose (x, y, z, qw, qx, qy, qz), in the objects' order,
    and the reasons why earlier drops of the same generator were rejected."""

    poses: list[np.ndarray]
    rejected: list[str]
    settle_time_s: float


def random_quaternion(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random orientation (w, x, y, z): a normalised 4-D Gaussian draw."""
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def _rotation(quat: np.ndarray) -> np.ndarray:
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=float))
    return mat.reshape(3, 3)


def _drop_model(
    assets: Sequence[ObjectLike], cfg: SceneConfig, physics: PhysicsConfig
) -> tuple[mujoco.MjModel, np.ndarray]:
    """The drop model and its wall geom ids. Objects start parked (see the module docstring)."""
    parked = [
        np.array([_PARK_XYZ[0], _PARK_XYZ[1] + _PARK_STEP_M * i, _PARK_XYZ[2], 1.0, 0, 0, 0])
        for i in range(len(assets))
    ]
    spec = compose_posed(assets, parked, cfg, None, physics)
    spec.modelname = "hsqbench_pile_drop"
    pile, ws = cfg.pile, cfg.workspace
    half = np.asarray(pile.box_size_m) / 2 + pile.wall_thickness_m / 2
    t, h = pile.wall_thickness_m / 2, pile.wall_height_m / 2
    span = np.asarray(pile.box_size_m) / 2 + pile.wall_thickness_m
    walls = {
        "x-": ([-half[0], 0.0], [t, span[1]]),
        "x+": ([half[0], 0.0], [t, span[1]]),
        "y-": ([0.0, -half[1]], [span[0], t]),
        "y+": ([0.0, half[1]], [span[0], t]),
    }
    for side, (offset, size) in walls.items():
        geom = spec.worldbody.add_geom(
            name=WALL_PREFIX + side,
            type=mujoco.mjtGeom.mjGEOM_BOX,
            pos=[ws.centre_xy_m[0] + offset[0], ws.centre_xy_m[1] + offset[1], h],
            size=[size[0], size[1], h],
        )
        physics.table.apply(geom)
    for body in spec.bodies:
        if body.name.startswith(OBJECT_PREFIX):
            # Compiled with gravity compensation so that the model keeps computing it (MuJoCo
            # skips it when no body has any); switched per body while dropping.
            body.gravcomp = 1.0
    model = spec.compile()
    walls_ids = np.array([model.geom(WALL_PREFIX + s).id for s in walls])
    return model, walls_ids


class _Drop:
    """One drop model, reused across the attempts of a pile."""

    def __init__(self, assets: Sequence[ObjectLike], cfg: SceneConfig, physics: PhysicsConfig):
        self.assets, self.cfg, self.physics = list(assets), cfg, physics
        self.model, self.wall_ids = _drop_model(assets, cfg, physics)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.body_ids = np.array([m.body(OBJECT_PREFIX + a.name).id for a in assets])
        self.qpos_adr = [int(m.jnt_qposadr[m.body_jntadr[b]]) for b in self.body_ids]
        self.qvel_adr = [int(m.jnt_dofadr[m.body_jntadr[b]]) for b in self.body_ids]
        self.geoms = [
            np.flatnonzero((m.geom_bodyid == b) & (m.geom_contype > 0)) for b in self.body_ids
        ]
        self.contype = m.geom_contype.copy()
        self.conaffinity = m.geom_conaffinity.copy()
        self.vertices = [hull_vertices(a) for a in assets]
        table = m.geom("table").id
        self.table_top_z = float(m.geom_pos[table, 2] + m.geom_size[table, 2])

    def reset(self) -> None:
        m = self.model
        mujoco.mj_resetData(m, self.data)
        m.geom_contype[:], m.geom_conaffinity[:] = self.contype, self.conaffinity
        for i, geoms in enumerate(self.geoms):
            m.body_gravcomp[self.body_ids[i]] = 1.0
            m.geom_contype[geoms] = 0
            m.geom_conaffinity[geoms] = 0
        mujoco.mj_forward(m, self.data)

    def world_vertices(self, i: int) -> np.ndarray:
        b = self.body_ids[i]
        return self.vertices[i] @ self.data.xmat[b].reshape(3, 3).T + self.data.xpos[b]

    def release(self, i: int, pos: np.ndarray, quat: np.ndarray) -> None:
        m, d = self.model, self.data
        d.qpos[self.qpos_adr[i] : self.qpos_adr[i] + 7] = [*pos, *quat]
        d.qvel[self.qvel_adr[i] : self.qvel_adr[i] + 6] = 0.0
        m.body_gravcomp[self.body_ids[i]] = 0.0
        m.geom_contype[self.geoms[i]] = self.contype[self.geoms[i]]
        m.geom_conaffinity[self.geoms[i]] = self.conaffinity[self.geoms[i]]
        mujoco.mj_forward(m, d)

    def remove_walls(self) -> None:
        self.model.geom_contype[self.wall_ids] = 0
        self.model.geom_conaffinity[self.wall_ids] = 0

    def settle(self, upto: int) -> tuple[float, float]:
        return settle(
            self.model, self.data, self.body_ids[:upto], self.physics, self.cfg.pile.settle_time_s
        )

    def poses(self) -> list[np.ndarray]:
        return [self.data.qpos[a : a + 7].copy() for a in self.qpos_adr]


def _drop_pose(
    drop: _Drop, i: int, heap_top_z: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray] | None:
    """A random orientation whose bounding box fits between the walls, a random position in
    the box that keeps it there, its lowest point ``drop_clearance_m`` above the heap; None
    when no orientation of ``max_orientation_tries`` fits."""
    pile, ws = drop.cfg.pile, drop.cfg.workspace
    inner = np.asarray(pile.box_size_m) - 2 * _WALL_GAP_M
    for _ in range(pile.max_orientation_tries):
        quat = random_quaternion(rng)
        v = drop.vertices[i] @ _rotation(quat).T
        lo, hi = v.min(axis=0), v.max(axis=0)
        slack = inner - (hi - lo)[:2]
        if np.any(slack < 0):
            continue
        centre = np.asarray(ws.centre_xy_m) + rng.uniform(-slack / 2, slack / 2)
        xy = centre - (lo + hi)[:2] / 2
        z = heap_top_z + pile.drop_clearance_m - lo[2]
        return np.array([xy[0], xy[1], z]), quat
    return None


def heap_problem(
    names: Sequence[str],
    vertices: Sequence[np.ndarray],
    speed: float,
    table_top_z: float,
    cfg: SceneConfig,
    physics: PhysicsConfig,
) -> str | None:
    """Why a settled heap is not a pile to use, or None: something still moves (``speed``, the
    largest object speed at the end of settling), or an object (its hull ``vertices``, world
    frame) is off the table or not wholly inside the workspace."""
    if speed >= physics.settle_speed_mps:
        return (
            f"the heap still moves at {speed:.3f} at the end of settling "
            f"(at rest: under {physics.settle_speed_mps})"
        )
    ws = cfg.workspace
    lo = np.asarray(ws.centre_xy_m) - np.asarray(ws.size_m) / 2
    hi = np.asarray(ws.centre_xy_m) + np.asarray(ws.size_m) / 2
    for name, v in zip(names, vertices, strict=True):
        if v[:, 2].min() < table_top_z - _SINK_TOLERANCE_M:
            return f"{name} fell off the table"
        if np.any(v[:, :2] < lo) or np.any(v[:, :2] > hi):
            return f"{name} ended (partly) outside the workspace"
        if v[:, 2].max() > table_top_z + ws.height_m:
            return f"{name} reaches above the workspace's {ws.height_m} m height"
    return None


def _problem(drop: _Drop, speed: float) -> str | None:
    names = [a.name for a in drop.assets]
    vertices = [drop.world_vertices(i) for i in range(len(names))]
    return heap_problem(names, vertices, speed, drop.table_top_z, drop.cfg, drop.physics)


def _attempt(drop: _Drop, rng: np.random.Generator) -> tuple[str | None, float]:
    """Drop every object once; (why this drop is rejected or None, simulated settle time)."""
    drop.reset()
    names = [a.name for a in drop.assets]
    heap_top, total_s = drop.table_top_z, 0.0
    try:
        for i in range(len(names)):
            pose = _drop_pose(drop, i, heap_top, rng)
            if pose is None:
                return (
                    f"{names[i]}: no orientation of {drop.cfg.pile.max_orientation_tries} fits "
                    f"the {list(drop.cfg.pile.box_size_m)} m box"
                ), total_s
            drop.release(i, *pose)
            # Until at rest or settle_time_s: a heap between walls can keep creeping slowly
            # (an object leaning on a wall); the next drop then comes anyway, as in VGN's
            # fixed waits, and only the heap without walls must come to rest.
            total_s += drop.settle(i + 1)[0]
            heap_top = max(heap_top, float(drop.world_vertices(i)[:, 2].max()))
        drop.remove_walls()
        t, speed = drop.settle(len(names))
        total_s += t
    except RuntimeError as exc:  # diverged
        return str(exc), total_s
    return _problem(drop, speed), total_s


def drop_pile(
    assets: Sequence[ObjectLike],
    cfg: SceneConfig,
    physics: PhysicsConfig,
    rng: np.random.Generator,
    accept: Callable[[list[np.ndarray]], str | None] | None = None,
) -> PileDrop:
    """Drop ``assets`` into a pile (module docstring), drawing from ``rng``.

    ``accept``: a further check of a drop's settled poses (the scene builder's: the pile in the
    final scene, with the robot, is at rest on the table too); its reason rejects the drop.

    Raises:
        PileError: none of ``pile.max_drop_attempts`` drops gave a usable pile (names why).
    """
    ws = cfg.workspace
    if any(b > w for b, w in zip(cfg.pile.box_size_m, ws.size_m, strict=True)):
        raise ValueError(
            f"pile.box_size_m {list(cfg.pile.box_size_m)} must fit inside workspace.size_m "
            f"{list(ws.size_m)} in the scene config: the heap is checked to lie in the workspace"
        )
    drop = _Drop(assets, cfg, physics)
    rejected: list[str] = []
    total_s = 0.0
    for _ in range(cfg.pile.max_drop_attempts):
        why, t = _attempt(drop, rng)
        total_s += t
        if why is None and accept is not None:
            why = accept(drop.poses())
        if why is None:
            return PileDrop(drop.poses(), rejected, total_s)
        rejected.append(why)
    names = [a.name for a in assets]
    raise PileError(
        f"no pile of {names} settled at rest on the table inside the workspace in "
        f"{cfg.pile.max_drop_attempts} drops ({'; '.join(rejected)}); raise pile.max_drop_attempts "
        "or pile.settle_time_s, or widen the workspace"
    )
