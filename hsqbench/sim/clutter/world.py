"""VGN/GIGA's clutter-removal world in MuJoCo: their table and workspace cube, their camera(s),
the round's objects (each at its own size scale) and the free hand.

Frame: theirs. The workspace cube spans [0, size] on x, y and z; the table top lies at
``table_height_m`` (their ``table_height = finger_depth``). Objects not in play (not yet placed,
grasped, or fallen out of the workspace) are parked far away, floating, without collisions;
the hand waits parked out of view between grasps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.clutter.config import ClutterCameraConfig, ClutterConfig
from hsqbench.sim.clutter.hand import FreeHand, add_free_hand
from hsqbench.sim.objects import ObjectLike, add_object_body
from hsqbench.sim.physics import PhysicsConfig, apply_physics
from hsqbench.sim.robot import RobotConfig
from hsqbench.sim.scene.info import DepthCamera

Array = NDArray[np.float64]
OBJECT_PREFIX = "obj/"
TABLE = "table"
WALL_PREFIX = "pile_wall"
CAMERA_PREFIX = "clutter_cam"
#: Their cloud's crop lies this far inside the cube's sides (``place_table``: lx, ly = 0.02).
CROP_INSET_M = 0.02
#: Geom group of the pile box's walls: not one the cameras draw (they are gone before a look).
WALL_GROUP = 4


def camera_eyes(cam: ClutterCameraConfig, size_m: float) -> tuple[Array, Array]:
    """(eyes (V, 3), look-at point (3,)) of their ``camera_on_sphere`` views: the side view, or
    ``n_views`` on a ring (azimuth ``2 pi k / n``)."""
    if cam.views == "side":
        target = np.array([size_m / 2, size_m / 2, size_m * cam.side_origin_height_fraction])
        polar, azimuths = np.radians(cam.side_polar_deg), [np.radians(cam.side_azimuth_deg)]
    else:
        target = np.array([size_m / 2, size_m / 2, size_m * cam.ring_origin_height_fraction])
        polar = np.radians(cam.ring_polar_deg)
        azimuths = 2.0 * np.pi * np.arange(cam.n_views) / cam.n_views
    r = cam.radius_factor * size_m
    eyes = np.array(
        [
            target
            + r * np.array([np.sin(polar) * np.cos(a), np.sin(polar) * np.sin(a), np.cos(polar)])
            for a in azimuths
        ]
    )
    return eyes, target


def look_at_quat(eye: Array, target: Array) -> Array:
    """MuJoCo camera quaternion (w, x, y, z) looking from ``eye`` at ``target``, image up
    toward +z (the camera looks along its -z, y up)."""
    forward = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([right, up, -forward]).ravel())
    return quat


def add_cameras(worldbody: mujoco.MjsBody, cam: ClutterCameraConfig, size_m: float,
                origin: Array | None = None) -> None:  # fmt: skip
    """Their camera(s) (:func:`camera_eyes`) on ``worldbody``, their frame's origin at
    ``origin`` (None: the world's)."""
    shift = np.zeros(3) if origin is None else np.asarray(origin, float)
    eyes, target = camera_eyes(cam, size_m)
    for i, eye in enumerate(eyes):
        worldbody.add_camera(
            name=f"{CAMERA_PREFIX}{i}",
            pos=list(map(float, eye + shift)),
            quat=list(map(float, look_at_quat(eye, target))),
            fovy=cam.fovy_deg,
            resolution=[cam.width_px, cam.height_px],
        )


def outside_cube(position: Array, size_m: float) -> bool:
    """Their workspace test: a position (in their frame) outside [0, size] on any axis."""
    return bool(np.any(position < 0.0) or np.any(position > size_m))


@dataclass
class ClutterWorld:
    """A compiled clutter-removal world and its handles.

    Attributes:
        objects: the round's object names; ``scales``: each one's size scale.
        in_play: names of the objects on the table now (placed, not removed).
    """

    model: mujoco.MjModel
    data: mujoco.MjData
    config: ClutterConfig
    objects: list[str]
    scales: dict[str, float]
    body_ids: dict[str, int]
    geom_ids: dict[str, NDArray[np.int_]]
    cameras: tuple[DepthCamera, ...]
    hand: FreeHand
    table_geom: int
    wall_geoms: NDArray[np.int_]
    in_play: list[str] = field(default_factory=list)
    #: The objects' assets by name (what the world was built from).
    assets: dict[str, ObjectLike] = field(default_factory=dict)
    #: Wall seconds of building and generating the scene.
    build_s: float = 0.0

    @property
    def table_z(self) -> float:
        return self.config.scene.table_height_m

    @property
    def support_plane(self) -> Array:
        return np.array([0.0, 0.0, 1.0, -self.table_z])

    def crop_box(self) -> tuple[Array, Array]:
        """Their cloud's crop (``place_table``'s bounds): 2 cm inside the cube's sides, from the
        table top to the cube's top (the table itself goes by perception's table margin)."""
        sc = self.config.scene
        lo = np.array([CROP_INSET_M, CROP_INSET_M, sc.table_height_m])
        hi = np.array([sc.size_m - CROP_INSET_M, sc.size_m - CROP_INSET_M, sc.size_m])
        return lo, hi

    # ---- objects -------------------------------------------------------------------------------
    def _qadr(self, name: str) -> int:
        return int(self.model.jnt_qposadr[self.model.body_jntadr[self.body_ids[name]]])

    def _dadr(self, name: str) -> int:
        return int(self.model.jnt_dofadr[self.model.body_jntadr[self.body_ids[name]]])

    def set_pose(self, name: str, position: Array, quat: Array) -> None:
        a, d = self._qadr(name), self._dadr(name)
        self.data.qpos[a : a + 3] = position
        self.data.qpos[a + 3 : a + 7] = quat
        self.data.qvel[d : d + 6] = 0.0

    def pose(self, name: str) -> Array:
        """(x, y, z, qw, qx, qy, qz) of an object's frame now."""
        a = self._qadr(name)
        return self.data.qpos[a : a + 7].copy()

    def com(self, name: str) -> Array:
        """Centre of mass of an object now (their body position)."""
        return self.data.xipos[self.body_ids[name]].copy()

    def speed(self, name: str) -> float:
        """Linear speed of an object's frame now, m/s (their ``get_velocity``)."""
        d = self._dadr(name)
        return float(np.linalg.norm(self.data.qvel[d : d + 3]))

    def bring_in(self, name: str, position: Array, quat: Array) -> None:
        """Put a parked object into play at a pose, collisions on, under gravity."""
        body = self.body_ids[name]
        self.model.body_gravcomp[body] = 0.0
        self.model.geom_contype[self.geom_ids[name]] = 1
        self.model.geom_conaffinity[self.geom_ids[name]] = 1
        self.set_pose(name, position, quat)
        if name not in self.in_play:
            self.in_play.append(name)
        mujoco.mj_forward(self.model, self.data)

    def park(self, name: str) -> None:
        """Take an object out of play: far away, floating, without collisions."""
        body = self.body_ids[name]
        self.model.body_gravcomp[body] = 1.0
        self.model.geom_contype[self.geom_ids[name]] = 0
        self.model.geom_conaffinity[self.geom_ids[name]] = 0
        k = self.objects.index(name)
        self.set_pose(name, np.array([-10.0 - k, -10.0, 1.0]), np.array([1.0, 0, 0, 0]))
        if name in self.in_play:
            self.in_play.remove(name)
        mujoco.mj_forward(self.model, self.data)

    def touching_objects(self, name: str) -> list[str]:
        """Objects in play in contact with ``name`` now."""
        n = self.data.ncon
        if n == 0:
            return []
        bodies = self.model.geom_bodyid[self.data.contact.geom[:n]]
        me = self.body_ids[name]
        others = {int(b) for pair in bodies if me in pair for b in pair if b != me}
        return [o for o in self.in_play if self.body_ids[o] in others]

    def remove_walls(self) -> None:
        self.model.geom_contype[self.wall_geoms] = 0
        self.model.geom_conaffinity[self.wall_geoms] = 0

    # ---- their wait_for_objects_to_rest / remove_objects_outside_workspace --------------------
    def wait_to_rest(self, timeout_s: float) -> float:
        """Run in ``rest_check_s`` chunks until every object in play moves slower than
        ``rest_speed_mps``, at most ``timeout_s`` (checked after each chunk, as theirs).
        Returns the simulated seconds run."""
        sc = self.config.scene
        steps = max(1, round(sc.rest_check_s / self.model.opt.timestep))
        t0 = self.data.time
        while self.data.time - t0 < timeout_s - 1e-9:
            mujoco.mj_step(self.model, self.data, nstep=steps)
            if all(self.speed(n) <= sc.rest_speed_mps for n in self.in_play):
                break
        return float(self.data.time - t0)

    def outside(self, name: str) -> bool:
        """Their workspace test: the object's position outside [0, size] on any axis."""
        return outside_cube(self.com(name), self.config.scene.size_m)

    def remove_and_wait(self) -> list[str]:
        """Their ``remove_and_wait``: come to rest, take out objects outside the workspace,
        again until none is taken out. Returns the names taken out."""
        out: list[str] = []
        while True:
            self.wait_to_rest(self.config.scene.rest_timeout_s)
            gone = [n for n in self.in_play if self.outside(n)]
            if not gone:
                return out
            for n in gone:
                self.park(n)
            out += gone


def compose_world(
    assets: Sequence[ObjectLike],
    scales: Sequence[float],
    config: ClutterConfig,
    robot: RobotConfig,
    physics: PhysicsConfig,
    walls: bool,
) -> mujoco.MjSpec:
    """The world's spec: table, camera(s), the objects parked, the pile box's walls when
    ``walls``, and the free hand parked."""
    sc, cam = config.scene, config.camera
    spec = mujoco.MjSpec()
    spec.modelname = "hsqbench_clutter"
    apply_physics(spec, physics)
    spec.visual.global_.offwidth = max(640, cam.width_px)
    spec.visual.global_.offheight = max(480, cam.height_px)
    half, top = sc.table_half_m, sc.table_height_m
    table = spec.worldbody.add_geom(
        name=TABLE,
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[half, half, 0.025],
        pos=[sc.size_m / 2, sc.size_m / 2, top - 0.025],
        rgba=[0.6, 0.5, 0.4, 1.0],
    )
    physics.table.apply(table)
    add_cameras(spec.worldbody, cam, sc.size_m)
    if walls:
        lo, hi = np.array(sc.pile_box_lo_m), np.array(sc.pile_box_hi_m)
        t, h = sc.pile_wall_thickness_m, sc.pile_wall_height_m
        mid, span = 0.5 * (lo + hi), hi - lo
        for k, (pos, size) in enumerate(
            [
                ((lo[0] - t / 2, mid[1]), (t / 2, span[1] / 2 + t)),
                ((hi[0] + t / 2, mid[1]), (t / 2, span[1] / 2 + t)),
                ((mid[0], lo[1] - t / 2), (span[0] / 2 + t, t / 2)),
                ((mid[0], hi[1] + t / 2), (span[0] / 2 + t, t / 2)),
            ]
        ):
            wall = spec.worldbody.add_geom(
                name=f"{WALL_PREFIX}{k}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                size=[size[0], size[1], h / 2],
                pos=[pos[0], pos[1], top + h / 2],
                group=WALL_GROUP,
            )
            physics.table.apply(wall)
    for k, (asset, s) in enumerate(zip(assets, scales, strict=True)):
        add_object_body(
            spec.worldbody,
            spec,
            asset,
            OBJECT_PREFIX + asset.name,
            np.array([-10.0 - k, -10.0, 1.0]),
            np.array([1.0, 0.0, 0.0, 0.0]),
            physics.objects,
            mass_scale=physics.object_mass_scale,
            size_scale=float(s),
        )
    add_free_hand(spec, robot, np.array(config.hand.park_m))
    return spec


def compile_world(
    assets: Sequence[ObjectLike],
    scales: Sequence[float],
    config: ClutterConfig,
    robot: RobotConfig,
    physics: PhysicsConfig,
    walls: bool = False,
) -> ClutterWorld:
    """Compile :func:`compose_world` with every object parked (no collisions, floating)."""
    spec = compose_world(assets, scales, config, robot, physics, walls)
    model = spec.compile()
    data = mujoco.MjData(model)
    names = [a.name for a in assets]
    body_ids = {n: model.body(OBJECT_PREFIX + n).id for n in names}
    # The collision hulls (the visual meshes never collide: add_object_body set them 0).
    geom_ids = {
        n: np.flatnonzero((model.geom_bodyid == b) & (model.geom_contype != 0))
        for n, b in body_ids.items()
    }
    cam = config.camera
    cameras = tuple(
        DepthCamera(
            name=model.camera(i).name,
            width_px=cam.width_px,
            height_px=cam.height_px,
            fovy_deg=float(model.cam_fovy[i]),
            min_range_m=cam.min_range_m,
            max_range_m=cam.max_range_m,
        )
        for i in range(model.ncam)
    )
    walls_ids = np.array(
        [g for g in range(model.ngeom) if (model.geom(g).name or "").startswith(WALL_PREFIX)],
        dtype=int,
    )
    world = ClutterWorld(
        model=model,
        data=data,
        config=config,
        objects=names,
        scales={n: float(s) for n, s in zip(names, scales, strict=True)},
        body_ids=body_ids,
        geom_ids=geom_ids,
        cameras=cameras,
        hand=FreeHand(model),
        table_geom=model.geom(TABLE).id,
        wall_geoms=walls_ids,
        assets={a.name: a for a in assets},
    )
    for n in names:
        world.park(n)
    world.hand.teleport(data, np.array(config.hand.park_m), np.eye(3))
    return world
