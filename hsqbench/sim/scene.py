"""Benchmark scenes: a table, the Panda at its back edge, a bin, two depth cameras and objects.

World frame = the Panda's base frame: origin at the base on the table top, x forward over the
table, y to the robot's left, z up. The table top is the plane z = 0. The static world (table,
bin, floor, lights, cameras) is MJCF in ``scenes/`` (:func:`load_world`); workspace and placement
rules come from ``configs/scene.yaml``; the robot from :mod:`hsqbench.sim.robot`; the physics
options from :mod:`hsqbench.sim.physics`.

Kinds:

- ``isolated``: one object, upright in its canonical pose with a random yaw, at a random position
  whose footprint lies inside the workspace.
- ``packed``: ``n_packed`` different objects, each upright with a random yaw, placed by rejection
  sampling so that no two footprints (rotated bounding rectangles grown by the margin) overlap.

Both are then settled (simulated with the arm holding its home pose) and the rest state is stored
as the keyframe ``initial``. Everything random comes from ``np.random.default_rng(seed)``.
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import mujoco
import numpy as np

from hsqbench.config import load_config
from hsqbench.sim.objects import ObjectLike, add_object_body, resolve_object
from hsqbench.sim.physics import PhysicsConfig, apply_physics, load_physics_config
from hsqbench.sim.robot import Panda, RobotConfig, load_panda_spec, load_robot_config

KINDS = ("isolated", "packed")
INITIAL_KEY = "initial"
OBJECT_PREFIX = "obj/"
BIN_GEOMS = tuple(f"bin/{p}" for p in ("bottom", "wall_x-", "wall_x+", "wall_y-", "wall_y+"))


@dataclass(frozen=True)
class WorkspaceConfig:
    centre_xy_m: tuple[float, float] = (0.5, 0.0)
    size_m: tuple[float, float] = (0.36, 0.5)
    height_m: float = 0.3


@dataclass(frozen=True)
class DepthCameraConfig:
    """Which cameras of the world file are depth cameras, and their range (what MJCF cannot
    say); image size and field of view are the cameras' own (``resolution``, ``fovy``)."""

    names: tuple[str, ...] = ("cam_left", "cam_right")
    min_range_m: float = 0.5
    max_range_m: float = 3.86


@dataclass(frozen=True)
class ViewerCameraConfig:
    """The world file's camera for pictures."""

    name: str = "viewer"


@dataclass(frozen=True)
class PlacementConfig:
    """How objects are put on the table (reasons in ``configs/scene.yaml``).

    ``pose``: ``upright`` (the mesh's own up, the paper's protocol) or ``resting`` (one of the
    object's stable resting poses, drawn by probability, :mod:`hsqbench.assets.resting`; poses
    less likely than ``min_resting_probability`` are not drawn). Either way a random yaw and
    position follow.
    """

    n_packed: int = 5
    margin_m: float = 0.02
    max_tries_per_object: int = 300
    max_scene_attempts: int = 20
    drop_height_m: float = 0.002
    pose: Literal["upright", "resting"] = "upright"
    min_resting_probability: float = 0.01

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_resting_probability < 1.0:
            raise ValueError(
                f"placement.min_resting_probability must be in [0, 1), got "
                f"{self.min_resting_probability}"
            )


@dataclass(frozen=True)
class SceneConfig:
    """``configs/scene.yaml``; see the comments there for every value's reason.

    ``world``: the static world's MJCF (table, bin, floor, lights, cameras), a name in
    ``scenes/`` or a path; see :func:`world_path`.
    """

    world: str = "world"
    workspace: WorkspaceConfig = field(default_factory=WorkspaceConfig)
    depth_cameras: DepthCameraConfig = field(default_factory=DepthCameraConfig)
    viewer_camera: ViewerCameraConfig = field(default_factory=ViewerCameraConfig)
    placement: PlacementConfig = field(default_factory=PlacementConfig)


def load_scene_config(path: str | Path | None = "scene") -> SceneConfig:
    """Load ``configs/scene.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(SceneConfig, path)


@dataclass(frozen=True)
class DepthCamera:
    """A depth camera of the scene: MuJoCo camera name, image size, field of view and range."""

    name: str
    width_px: int
    height_px: int
    fovy_deg: float
    min_range_m: float
    max_range_m: float


@dataclass
class SceneInfo:
    """What a built scene contains. Lengths in metres, world frame (= robot base frame).

    Attributes:
        kind, seed: how the scene was drawn.
        objects: names of the placed objects, in draw order.
        object_bodies: object name -> body name; ``object_body_ids``: -> body id.
        object_geom_ids: object name -> ids of its collision geoms.
        initial_poses: object name -> (7,) settled pose (x, y, z, qw, qx, qy, qz).
        depth_cameras: the two depth cameras; ``viewer_camera``: camera name for pictures.
        table_top_z: height of the table top; ``support_plane``: (a, b, c, d) with
            a x + b y + c z + d = 0 on the table top and (a, b, c) pointing up.
        table_geom_id: the table top's geom id.
        workspace_min, workspace_max: (3,) corners of the placement region (z from the table top).
        bin_min, bin_max: (3,) corners of the bin's inside; ``bin_geom_ids``: its geoms.
        robot_prefix, arm_joints, arm_actuators, finger_joints, gripper_actuator, tcp_site,
            hand_body: names of the robot's elements (see :class:`hsqbench.sim.robot.Panda`).
        initial_key: keyframe name of the settled state (``mj_resetDataKeyframe``).
        settle_time_s: simulated time the settling took; ``max_speed_after_settle``: largest
            object speed (m/s or rad/s) at its end.
        build_time_s: wall-clock time of :func:`build_scene`.
        resting_poses: object name -> index of the resting pose drawn
            (:func:`hsqbench.assets.resting.resting_poses`, most probable first), -1 upright.
    """

    kind: str
    seed: int
    objects: list[str]
    object_bodies: dict[str, str]
    object_body_ids: dict[str, int]
    object_geom_ids: dict[str, np.ndarray]
    initial_poses: dict[str, np.ndarray]
    depth_cameras: tuple[DepthCamera, ...]
    viewer_camera: str
    table_top_z: float
    support_plane: np.ndarray
    table_geom_id: int
    workspace_min: np.ndarray
    workspace_max: np.ndarray
    bin_min: np.ndarray
    bin_max: np.ndarray
    bin_geom_ids: np.ndarray
    robot_prefix: str
    arm_joints: tuple[str, ...]
    arm_actuators: tuple[str, ...]
    finger_joints: tuple[str, ...]
    gripper_actuator: str
    tcp_site: str
    hand_body: str
    initial_key: str = INITIAL_KEY
    settle_time_s: float = 0.0
    max_speed_after_settle: float = 0.0
    build_time_s: float = 0.0
    resting_poses: dict[str, int] = field(default_factory=dict)

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.depth_cameras)

    def reset(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Return ``data`` to the settled initial state."""
        mujoco.mj_resetDataKeyframe(model, data, model.key(self.initial_key).id)
        mujoco.mj_forward(model, data)


# ---- placement ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Footprint:
    """The minimum-area rectangle around an object's projection on the table, object frame.

    Placing this rectangle rather than the axis-aligned box matters for objects that lie
    diagonally in their mesh frame (the YCB hammer: 0.18 x 0.33 m axis-aligned, about
    0.10 x 0.33 m oriented), which otherwise make feasible packed draws look impossible.

    Attributes:
        extents_xy: side lengths (m), the first along ``angle_rad``.
        centre_xy: rectangle centre in the object frame (m).
        angle_rad: direction of the first side relative to the object's x axis.
    """

    extents_xy: np.ndarray
    centre_xy: np.ndarray
    angle_rad: float

    def object_pose(self, rect_xy: np.ndarray, rect_yaw: float) -> tuple[np.ndarray, float]:
        """Object origin (x, y) and yaw that put this rectangle at ``rect_xy`` with ``rect_yaw``."""
        yaw = float(
            np.arctan2(np.sin(rect_yaw - self.angle_rad), np.cos(rect_yaw - self.angle_rad))
        )
        c, s = np.cos(yaw), np.sin(yaw)
        offset = np.array(
            [
                c * self.centre_xy[0] - s * self.centre_xy[1],
                s * self.centre_xy[0] + c * self.centre_xy[1],
            ]
        )
        return np.asarray(rect_xy, dtype=float) - offset, yaw


def min_area_rectangle(points_xy: np.ndarray) -> Footprint:
    """Minimum-area enclosing rectangle of 2-D points: one side lies on a convex-hull edge."""
    from scipy.spatial import ConvexHull

    hull = points_xy[ConvexHull(points_xy).vertices]
    edges = np.roll(hull, -1, axis=0) - hull
    angles = np.arctan2(edges[:, 1], edges[:, 0])
    c, s = np.cos(angles)[:, None], np.sin(angles)[:, None]
    u = c * hull[None, :, 0] + s * hull[None, :, 1]  # coordinates along each candidate side
    v = -s * hull[None, :, 0] + c * hull[None, :, 1]
    width = u.max(axis=1) - u.min(axis=1)
    height = v.max(axis=1) - v.min(axis=1)
    k = int(np.argmin(width * height))
    cu = (u[k].max() + u[k].min()) / 2
    cv = (v[k].max() + v[k].min()) / 2
    centre = np.array(
        [
            np.cos(angles[k]) * cu - np.sin(angles[k]) * cv,
            np.sin(angles[k]) * cu + np.cos(angles[k]) * cv,
        ]
    )
    return Footprint(np.array([width[k], height[k]]), centre, float(angles[k]))


def object_footprint(asset: ObjectLike, rotation: np.ndarray | None = None) -> Footprint:
    """Oriented footprint from the collision hulls (turned by ``rotation``, a resting pose, when
    given); the axis-aligned box when there are no hulls."""
    paths = tuple(str(p) for p in asset.collision_meshes)
    if not paths:
        e = np.asarray(asset.extents[:2], dtype=float)
        return Footprint(e, np.zeros(2), 0.0)
    rot = None if rotation is None else tuple(np.asarray(rotation, float).ravel())
    return _hull_footprint(paths, tuple(os.stat(p).st_mtime_ns for p in paths), rot)


@functools.lru_cache(maxsize=256)
def _hull_vertices(paths: tuple[str, ...], mtimes_ns: tuple[int, ...]) -> np.ndarray:
    import trimesh

    return np.concatenate(
        [trimesh.load(path, force="mesh", process=False).vertices for path in paths]
    )


@functools.lru_cache(maxsize=256)
def _hull_footprint(
    paths: tuple[str, ...], mtimes_ns: tuple[int, ...], rotation: tuple[float, ...] | None
) -> Footprint:
    # Cached per hull files, their modification times and the pose: checking many packed draws
    # (hsqbench.experiment.seeds) reuses the objects' footprints instead of reloading hulls.
    vertices = _hull_vertices(paths, mtimes_ns)
    if rotation is not None:
        vertices = vertices @ np.asarray(rotation).reshape(3, 3).T
    return min_area_rectangle(vertices[:, :2])


def rested_base_z(asset: ObjectLike, rotation: np.ndarray) -> float:
    """Lowest point of the hulls turned by ``rotation``, object frame (0 for the identity)."""
    paths = tuple(str(p) for p in asset.collision_meshes)
    if not paths:
        return 0.0
    vertices = _hull_vertices(paths, tuple(os.stat(p).st_mtime_ns for p in paths))
    return float((vertices @ np.asarray(rotation, float)[2]).min())


def draw_rests(
    assets: Sequence[ObjectLike], placement: PlacementConfig, rng: np.random.Generator
) -> list[tuple[int, np.ndarray]] | None:
    """Each object's resting pose (index, rotation) drawn by probability; None when upright
    (nothing is drawn then, so upright scenes keep the random stream they always had)."""
    if placement.pose == "upright":
        return None
    from hsqbench.assets.resting import resting_poses

    out = []
    for asset in assets:
        poses = resting_poses(asset, placement.min_resting_probability)
        k = poses.draw(rng)
        out.append((k, poses.rotations[k]))
    return out


def footprint_corners(extents_xy: np.ndarray, xy: np.ndarray, yaw: float) -> np.ndarray:
    """(4, 2) corners of an object's bounding rectangle (centred on the object frame origin,
    as the asset frame is) after a yaw rotation and a translation."""
    hx, hy = 0.5 * np.asarray(extents_xy, dtype=float)
    local = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
    c, s = np.cos(yaw), np.sin(yaw)
    return local @ np.array([[c, s], [-s, c]]) + np.asarray(xy, dtype=float)


def rectangles_overlap(a: np.ndarray, b: np.ndarray, gap: float) -> bool:
    """Whether two convex quadrilaterals (4, 2) come closer than ``gap`` (separating axes).

    Each rectangle's edge normals are the candidate axes; the shapes are at least ``gap`` apart
    along an axis when the projections' intervals are separated by ``gap``. For rectangles the
    projection test on their four edge normals is exact for overlap; with ``gap`` > 0 it is
    conservative near corners (it may report a corner-to-corner pair as closer than it is).
    """
    axes = []
    for poly in (a, b):
        edges = np.roll(poly, -1, axis=0) - poly
        normals = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
        axes.append(normals[:2] / np.linalg.norm(normals[:2], axis=1, keepdims=True))
    axes = np.concatenate(axes)
    pa, pb = a @ axes.T, b @ axes.T
    separated = (pa.min(axis=0) >= pb.max(axis=0) + gap) | (pb.min(axis=0) >= pa.max(axis=0) + gap)
    return not bool(separated.any())


class PlacementError(ValueError):
    """The objects cannot be placed apart inside the workspace (with the given random stream)."""


def _inside(corners: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    return bool(np.all(corners >= lo) and np.all(corners <= hi))


def place_objects(
    extents_xy: Sequence[np.ndarray],
    names: Sequence[str],
    workspace_lo: np.ndarray,
    workspace_hi: np.ndarray,
    placement: PlacementConfig,
    rng: np.random.Generator,
) -> list[tuple[np.ndarray, float]]:
    """Positions (x, y) and yaws (rad) of footprints that lie inside the workspace and keep
    ``margin_m`` from each other. Larger footprints are placed first.

    Raises:
        PlacementError: when an object cannot fit the workspace at any yaw, or no layout was
            found within the configured tries (names the objects and the areas involved).
    """
    ext = [np.asarray(e, dtype=float) for e in extents_xy]
    size = workspace_hi - workspace_lo
    for name, e in zip(names, ext, strict=True):
        if min(e) > min(size) or max(e) > np.hypot(*size):
            raise PlacementError(
                f"object {name!r} (footprint {e[0]:.3f} x {e[1]:.3f} m) cannot fit the "
                f"{size[0]:.2f} x {size[1]:.2f} m workspace; enlarge workspace.size_m in scene.yaml"
            )
    order = np.argsort([-e[0] * e[1] for e in ext], kind="stable")
    for _ in range(placement.max_scene_attempts):
        placed: dict[int, tuple[np.ndarray, float, np.ndarray]] = {}
        for i in order:
            for _ in range(placement.max_tries_per_object):
                yaw = float(rng.uniform(-np.pi, np.pi))
                xy = rng.uniform(workspace_lo, workspace_hi)
                corners = footprint_corners(ext[i], xy, yaw)
                if not _inside(corners, workspace_lo, workspace_hi):
                    continue
                if any(
                    rectangles_overlap(corners, other, placement.margin_m)
                    for _, _, other in placed.values()
                ):
                    continue
                placed[int(i)] = (xy, yaw, corners)
                break
            else:
                break
        if len(placed) == len(ext):
            return [(placed[i][0], placed[i][1]) for i in range(len(ext))]
    area = sum(float(e[0] * e[1]) for e in ext)
    raise PlacementError(
        f"could not place {list(names)} without contact in the {size[0]:.2f} x {size[1]:.2f} m "
        f"workspace after {placement.max_scene_attempts} attempts (footprints cover "
        f"{area:.3f} m^2 of {size[0] * size[1]:.3f} m^2 before the {placement.margin_m} m margin); "
        "choose fewer or smaller objects, or enlarge the workspace"
    )


# ---- composition -------------------------------------------------------------------------------


def world_path(cfg: SceneConfig) -> Path:
    """The world file: ``scenes/<world>.xml`` for a name, else the path given."""
    from hsqbench.settings import SCENES_DIR

    path = Path(cfg.world)
    if path.suffix != ".xml" and len(path.parts) == 1:
        path = SCENES_DIR / f"{cfg.world}.xml"
    if not path.is_file():
        raise FileNotFoundError(
            f"scene world file {path} does not exist (world: {cfg.world!r} in the scene config "
            "names a file in scenes/ or a path)"
        )
    return path


def world_files(cfg: SceneConfig) -> dict[str, str]:
    """The text of the world file and of every MJCF file beside it (those it may include), by
    file name: what a run's config hash covers of the scene's geometry."""
    folder = world_path(cfg).parent
    return {p.name: p.read_text() for p in sorted(folder.glob("*.xml"))}


def load_world(cfg: SceneConfig, physics: PhysicsConfig) -> mujoco.MjSpec:
    """The static world (``scenes/world.xml`` and the files it includes) as a spec, with the
    physics options and the table's contact parameters on the table top and the bin."""
    path = world_path(cfg)
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:
        raise ValueError(f"{path}: MuJoCo cannot read the scene world ({exc})") from exc
    apply_physics(spec, physics)
    names = {g.name for g in spec.geoms}
    missing = [n for n in ("table", *BIN_GEOMS) if n not in names]
    if missing:
        raise ValueError(f"{path}: the world needs geoms named {missing} (the harness reads them)")
    for geom in spec.geoms:
        if geom.name == "table" or geom.name.startswith("bin/"):
            physics.table.apply(geom)
    return spec


def draw_object_names(kind: str, n_packed: int, rng: np.random.Generator) -> list[str]:
    """Names drawn from the paper's 15 YCB objects (those the library has): one for
    ``isolated``, ``n_packed`` different ones for ``packed``. The paper's set, not the whole
    library: its packed draws are known to fit the workspace (a plate, a skillet lid and a chain
    with two others often do not)."""
    from hsqbench.assets.library import ycb_names
    from hsqbench.experiment.config import YCB_OBJECTS

    if kind not in KINDS:
        raise ValueError(f"unknown scene kind {kind!r}; known: {list(KINDS)}")
    known = set(ycb_names())
    pool = [n for n in YCB_OBJECTS if n in known]
    count = 1 if kind == "isolated" else n_packed
    if count > len(pool):
        raise ValueError(f"cannot draw {count} different objects from {len(pool)}: {pool}")
    return [pool[i] for i in rng.choice(len(pool), count, replace=False)]


def _resolve_objects(
    kind: str,
    objects: Sequence[str | ObjectLike] | str | ObjectLike | None,
    n_packed: int,
    rng: np.random.Generator,
) -> list[ObjectLike]:
    if kind not in KINDS:
        raise ValueError(f"unknown scene kind {kind!r}; known: {list(KINDS)}")
    chosen: list[str | ObjectLike]
    if objects is None:
        chosen = list(draw_object_names(kind, n_packed, rng))
    elif isinstance(objects, str) or not isinstance(objects, Sequence):
        chosen = [objects]
    else:
        chosen = list(objects)
    if kind == "isolated" and len(chosen) != 1:
        raise ValueError(f"an isolated scene has one object, got {len(chosen)}")
    if not chosen:
        raise ValueError("a packed scene needs at least one object")
    names = [o if isinstance(o, str) else o.name for o in chosen]
    if len(set(names)) != len(names):
        raise ValueError(f"objects must be different, got {names}")
    return [resolve_object(o) for o in chosen]


def layout_objects(
    assets: Sequence[ObjectLike],
    cfg: SceneConfig,
    rng: np.random.Generator,
    rests: Sequence[tuple[int, np.ndarray]] | None = None,
) -> list[tuple[np.ndarray, float]]:
    """Object origins (x, y) and yaws (rad) with the footprints apart inside the workspace.

    The placement of :func:`build_scene`, without a MuJoCo model: oriented footprints from the
    collision hulls (:func:`object_footprint`, each turned by its resting pose in ``rests``),
    then :func:`place_objects`.

    Raises:
        PlacementError: no layout was found (see :func:`place_objects`).
    """
    ws = cfg.workspace
    lo = np.asarray(ws.centre_xy_m) - np.asarray(ws.size_m) / 2
    hi = np.asarray(ws.centre_xy_m) + np.asarray(ws.size_m) / 2
    rotations = [None] * len(assets) if rests is None else [r for _, r in rests]
    prints = [object_footprint(a, r) for a, r in zip(assets, rotations, strict=True)]
    rect_poses = place_objects(
        [f.extents_xy for f in prints], [a.name for a in assets], lo, hi, cfg.placement, rng
    )
    return [f.object_pose(xy, yaw) for f, (xy, yaw) in zip(prints, rect_poses, strict=True)]


def packed_placeable(
    objects: Sequence[str | ObjectLike], seed: int, scene_config: SceneConfig | None = None
) -> bool:
    """Whether ``build_scene("packed", objects, seed)`` can place ``objects`` apart.

    Exact, not an estimate: it runs the same seeded placement as :func:`build_scene` (the
    placement is a rejection sampler, so the answer belongs to this seed), from the footprints
    and the workspace only, without compiling a model (milliseconds; footprints are cached).
    Unknown or duplicate objects still raise ``ValueError``.
    """
    cfg = scene_config or load_scene_config()
    rng = np.random.default_rng(seed)
    assets = _resolve_objects("packed", objects, cfg.placement.n_packed, rng)
    rests = draw_rests(assets, cfg.placement, rng)
    try:
        layout_objects(assets, cfg, rng, rests)
    except PlacementError:
        return False
    return True


def compose_scene(
    assets: Sequence[ObjectLike],
    poses: Sequence[tuple[np.ndarray, float]],
    cfg: SceneConfig,
    robot: RobotConfig,
    physics: PhysicsConfig,
    rests: Sequence[tuple[int, np.ndarray]] | None = None,
) -> mujoco.MjSpec:
    """The scene spec: static parts, the robot at the origin, objects at (xy, yaw), each first
    turned into its resting pose when ``rests`` is given."""
    spec = load_world(cfg, physics)
    spec.modelname = "hsqbench_scene"
    spec.attach(load_panda_spec(robot), prefix=robot.prefix, frame=spec.worldbody.add_frame())
    z = cfg.placement.drop_height_m
    for i, (asset, (xy, yaw)) in enumerate(zip(assets, poses, strict=True)):
        quat = np.array([np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)])
        height = z
        if rests is not None:
            rotation = rests[i][1]
            rest = np.zeros(4)
            mujoco.mju_mat2Quat(rest, np.ascontiguousarray(rotation, float).ravel())
            turned = np.zeros(4)
            mujoco.mju_mulQuat(turned, quat, rest)
            quat, height = turned, z - rested_base_z(asset, rotation)
        add_object_body(
            spec.worldbody,
            spec,
            asset,
            OBJECT_PREFIX + asset.name,
            np.array([xy[0], xy[1], height]),
            quat,
            physics.objects,
            mass_scale=physics.object_mass_scale,
        )
    return spec


def settle(
    model: mujoco.MjModel, data: mujoco.MjData, body_ids: np.ndarray, physics: PhysicsConfig
) -> tuple[float, float]:
    """Step until every body in ``body_ids`` moves slower than ``settle_speed_mps`` (checked
    after a 0.1 s minimum), or ``settle_time_s`` has passed. Returns (time taken, max speed)."""
    dt = model.opt.timestep
    n_max = max(1, round(physics.settle_time_s / dt))
    n_min = min(n_max, round(0.1 / dt))
    check_every = max(1, round(0.02 / dt))
    speed = 0.0
    for i in range(1, n_max + 1):
        mujoco.mj_step(model, data)
        if not np.all(np.isfinite(data.qacc)):
            raise RuntimeError("simulation diverged while settling the scene")
        if i >= n_min and i % check_every == 0:
            speed = float(np.abs(data.cvel[body_ids]).max()) if len(body_ids) else 0.0
            if speed < physics.settle_speed_mps:
                return i * dt, speed
    speed = float(np.abs(data.cvel[body_ids]).max()) if len(body_ids) else 0.0
    return n_max * dt, speed


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
        kind: ``"isolated"`` or ``"packed"``.
        objects: object names (library) or objects; ``None`` draws by seed from the 15 YCB
            objects (one for isolated, ``n_packed`` different ones for packed).
        seed: the only source of randomness; the same seed gives the same scene.

    Returns:
        ``(spec, model, data, info)`` with ``data`` at the settled state (also keyframe
        ``initial``, in the model only: the spec's keyframe is empty).

    Raises:
        ValueError: unknown kind or object (the library lists the known names), duplicate
            objects, or a layout that cannot be placed.
    """
    t0 = time.perf_counter()
    cfg = scene_config or load_scene_config()
    robot = robot_config or load_robot_config()
    physics = physics_config or load_physics_config()
    rng = np.random.default_rng(seed)
    assets = _resolve_objects(kind, objects, cfg.placement.n_packed, rng)
    rests = draw_rests(assets, cfg.placement, rng)
    poses = layout_objects(assets, cfg, rng, rests)
    spec = compose_scene(assets, poses, cfg, robot, physics, rests)
    spec.add_key(name=INITIAL_KEY)
    model = spec.compile()
    data = mujoco.MjData(model)
    panda = Panda(model, robot.prefix)
    panda.reset_home(data)
    mujoco.mj_forward(model, data)

    names = [a.name for a in assets]
    bodies = {n: OBJECT_PREFIX + n for n in names}
    body_ids = {n: model.body(b).id for n, b in bodies.items()}
    settle_s, speed = settle(model, data, np.array(list(body_ids.values())), physics)
    key = model.key(INITIAL_KEY).id
    model.key_qpos[key] = data.qpos
    model.key_qvel[key] = 0.0
    model.key_ctrl[key] = data.ctrl
    model.key_time[key] = 0.0
    info = _describe(model, data, cfg, robot, kind, seed, names, bodies, body_ids, panda)
    info.settle_time_s, info.max_speed_after_settle = settle_s, speed
    info.resting_poses = {
        a.name: (-1 if rests is None else int(rests[i][0])) for i, a in enumerate(assets)
    }
    info.reset(model, data)
    info.build_time_s = time.perf_counter() - t0
    return spec, model, data, info


def _describe(model, data, cfg, robot, kind, seed, names, bodies, body_ids, panda) -> SceneInfo:
    geom_ids = {
        n: np.flatnonzero((model.geom_bodyid == b) & (model.geom_contype > 0))
        for n, b in body_ids.items()
    }
    poses = {}
    for n, b in body_ids.items():
        adr = model.jnt_qposadr[model.body_jntadr[b]]
        poses[n] = data.qpos[adr : adr + 7].copy()
    dc = cfg.depth_cameras
    cams = []
    for name in dc.names:
        cam = model.camera(name)
        width, height = (int(v) for v in model.cam_resolution[cam.id])
        fovy = float(model.cam_fovy[cam.id])
        cams.append(DepthCamera(name, width, height, fovy, dc.min_range_m, dc.max_range_m))
    ws = cfg.workspace
    ws_lo = np.array([*(np.asarray(ws.centre_xy_m) - np.asarray(ws.size_m) / 2), 0.0])
    ws_hi = np.array([*(np.asarray(ws.centre_xy_m) + np.asarray(ws.size_m) / 2), ws.height_m])
    bin_ids = np.array([model.geom(n).id for n in BIN_GEOMS])
    bin_lo, bin_hi = _bin_inside(model, bin_ids)
    table_id = model.geom("table").id
    top_z = float(model.geom_pos[table_id, 2] + model.geom_size[table_id, 2])
    return SceneInfo(
        kind=kind,
        seed=seed,
        objects=list(names),
        object_bodies=bodies,
        object_body_ids=body_ids,
        object_geom_ids=geom_ids,
        initial_poses=poses,
        depth_cameras=tuple(cams),
        viewer_camera=cfg.viewer_camera.name,
        table_top_z=top_z,
        support_plane=np.array([0.0, 0.0, 1.0, -top_z]),
        table_geom_id=table_id,
        workspace_min=ws_lo,
        workspace_max=ws_hi,
        bin_min=bin_lo,
        bin_max=bin_hi,
        bin_geom_ids=bin_ids,
        robot_prefix=robot.prefix,
        arm_joints=panda.arm_joint_names,
        arm_actuators=panda.arm_actuator_names,
        finger_joints=panda.finger_joint_names,
        gripper_actuator=panda.gripper_actuator_name,
        tcp_site=model.site(panda.tcp_site_id).name,
        hand_body=model.body(panda.hand_body_id).name,
    )


def _bin_inside(model: mujoco.MjModel, bin_ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Corners of the bin's inside: above the bottom, between the walls, up to the walls' top
    (the bin's box geoms are axis-aligned in the world file)."""
    pos, size = model.geom_pos[bin_ids], model.geom_size[bin_ids]
    bottom, walls = 0, {"x-": 1, "x+": 2, "y-": 3, "y+": 4}
    lo = np.array(
        [
            pos[walls["x-"], 0] + size[walls["x-"], 0],
            pos[walls["y-"], 1] + size[walls["y-"], 1],
            pos[bottom, 2] + size[bottom, 2],
        ]
    )
    hi = np.array(
        [
            pos[walls["x+"], 0] - size[walls["x+"], 0],
            pos[walls["y+"], 1] - size[walls["y+"], 1],
            (pos[1:, 2] + size[1:, 2]).max(),
        ]
    )
    return lo, hi
