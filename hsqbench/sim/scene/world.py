"""Composition: the static world (MJCF in ``scenes/``), the robot and the objects as one spec;
settling; and the :class:`SceneInfo` of a compiled scene."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from hsqbench.sim.objects import ObjectLike, add_object_body
from hsqbench.sim.physics import PhysicsConfig, apply_physics
from hsqbench.sim.robot import RobotConfig, load_panda_spec
from hsqbench.sim.scene.config import SceneConfig
from hsqbench.sim.scene.footprint import rested_base_z
from hsqbench.sim.scene.info import BIN_GEOMS, OBJECT_PREFIX, DepthCamera, SceneInfo


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
    z = cfg.placement.drop_height_m
    placed = []
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
        placed.append(np.array([xy[0], xy[1], height, *quat]))
    return compose_posed(assets, placed, cfg, robot, physics)


def compose_posed(
    assets: Sequence[ObjectLike],
    poses: Sequence[np.ndarray],
    cfg: SceneConfig,
    robot: RobotConfig | None,
    physics: PhysicsConfig,
    scales: Sequence[float] | None = None,
) -> mujoco.MjSpec:
    """The scene spec with each object at a full pose (x, y, z, qw, qx, qy, qz); the robot at
    the origin unless ``robot`` is None (a pile's drop model has no robot). ``scales``: each
    object's size scale (VGN/GIGA's scenes; default 1)."""
    spec = load_world(cfg, physics)
    spec.modelname = "hsqbench_scene"
    if robot is not None:
        spec.attach(load_panda_spec(robot), prefix=robot.prefix, frame=spec.worldbody.add_frame())
    sizes = [1.0] * len(assets) if scales is None else list(scales)
    for asset, pose, size in zip(assets, poses, sizes, strict=True):
        pose = np.asarray(pose, dtype=float)
        add_object_body(
            spec.worldbody,
            spec,
            asset,
            OBJECT_PREFIX + asset.name,
            pose[:3],
            pose[3:],
            physics.objects,
            mass_scale=physics.object_mass_scale,
            size_scale=float(size),
        )
    return spec


def settle(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    body_ids: np.ndarray,
    physics: PhysicsConfig,
    max_time_s: float | None = None,
) -> tuple[float, float]:
    """Step until every body in ``body_ids`` moves slower than ``settle_speed_mps`` (checked
    after a 0.1 s minimum), or ``max_time_s`` (default ``settle_time_s``) has passed. Returns
    (time taken, max speed)."""
    dt = model.opt.timestep
    limit_s = physics.settle_time_s if max_time_s is None else max_time_s
    n_max = max(1, round(limit_s / dt))
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


def come_to_rest(
    model: mujoco.MjModel, data: mujoco.MjData, body_ids: np.ndarray, physics: PhysicsConfig
) -> tuple[float, float]:
    """:func:`settle`, then, while an object still moves, stop the objects and let them go
    for ``rest_check_s`` again, up to ``rest_checks`` times. Returns (time taken, max speed).

    Objects have no rolling friction (condim 4), so one that ends a drop rolling on a round
    side (a cup rolling in circles) keeps rolling: the cameras would see it in one place and
    the hand would meet it in another. Stopped where it is, an object in a neutral rest stays
    put, and one caught mid-tumble falls on and is stopped again, nearer its rest."""
    t, speed = settle(model, data, body_ids, physics)
    if speed < physics.settle_speed_mps or not len(body_ids):
        return t, speed
    dofs = np.concatenate(
        [
            np.arange(model.body_dofadr[b], model.body_dofadr[b] + model.body_dofnum[b])
            for b in body_ids
        ]
    )
    n = max(1, round(physics.rest_check_s / model.opt.timestep))
    for _ in range(physics.rest_checks):
        data.qvel[dofs] = 0.0
        for _ in range(n):
            mujoco.mj_step(model, data)
        t += n * model.opt.timestep
        speed = float(np.abs(data.cvel[body_ids]).max())
        if speed < physics.settle_speed_mps:
            break
    return t, speed


def describe_scene(
    model, data, cfg, robot, kind, seed, names, bodies, body_ids, panda
) -> SceneInfo:
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
