"""What :meth:`RerunRecorder.on_scene <hsqbench.viz.rerun_recorder.RerunRecorder.on_scene>`
logs once per episode: the recording's name and default layout, a description of the scene, the
workspace box, and every body's mesh (static), with a static pose for bodies welded to the world
(entity paths in :mod:`hsqbench.viz.rerun_recorder`)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.viz.blueprint import episode_blueprint
from hsqbench.viz.config import ViewerConfig
from hsqbench.viz.rerun_cameras import camera_entity_name
from hsqbench.viz.scene_geometry import BodyMesh, body_meshes

WORKSPACE_COLOR = (200, 200, 200, 255)
#: MuJoCo geom group of the collision geoms (the scene's convention).
COLLISION_GROUP = 3


def _floor_centre(info: Any) -> NDArray[np.float64] | None:
    """The middle of the workspace's floor (where the objects stand), or None."""
    if not hasattr(info, "workspace_min"):
        return None
    lo, hi = np.asarray(info.workspace_min, float), np.asarray(info.workspace_max, float)
    return np.array([*(0.5 * (lo[:2] + hi[:2])), lo[2]])


def _layout(model: mujoco.MjModel, data: mujoco.MjData, info: Any) -> Any:
    """The episode's default layout (:mod:`hsqbench.viz.blueprint`), its eye on the side of the
    camera named first."""
    cameras = sorted(getattr(info, "depth_cameras", ()), key=lambda c: camera_entity_name(c.name))
    first = None
    if cameras and hasattr(info, "workspace_min"):  # the settled scene's kinematics are current
        first = data.cam_xpos[model.camera(cameras[0].name).id].copy()
    names = [camera_entity_name(c.name) for c in cameras]
    return episode_blueprint(names, first, _floor_centre(info))


def body_entity_path(rr: Any, model: mujoco.MjModel, info: Any, body: int) -> str:
    """``world/objects/<name>`` for an object, ``world/robot/<link>`` for a robot body (its name
    without ``info.robot_prefix``), else ``world/bodies/<name or id>``."""
    name = model.body(body).name
    objects = {int(v): k for k, v in getattr(info, "object_body_ids", {}).items()}
    if body in objects:
        return f"world/objects/{rr.escape_entity_path_part(objects[body])}"
    prefix = getattr(info, "robot_prefix", "")
    if prefix and name.startswith(prefix):
        return f"world/robot/{rr.escape_entity_path_part(name[len(prefix) :])}"
    return f"world/bodies/{rr.escape_entity_path_part(name or str(body))}"


def _mesh(rr: Any, mesh: BodyMesh) -> Any:
    return rr.Mesh3D(
        vertex_positions=mesh.vertices,
        triangle_indices=mesh.faces,
        vertex_colors=mesh.colors,
        vertex_normals=mesh.normals,
    )


def _log_description(
    rec: Any, rr: Any, model: mujoco.MjModel, data: mujoco.MjData, info: Any
) -> None:
    """The recording's name and layout, the scene as a text document and the workspace box."""
    kind, objects = getattr(info, "kind", "?"), list(getattr(info, "objects", []))
    seed = getattr(info, "seed", "?")
    rec.send_recording_name(f"{kind} {' '.join(objects)} seed {seed}")
    rec.send_blueprint(_layout(model, data, info))
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log(
        "scene",
        rr.TextDocument(
            f"**{kind}** scene, seed {seed}\n\nobjects: {', '.join(objects) or '-'}",
            media_type=rr.MediaType.MARKDOWN,
        ),
        static=True,
    )
    if hasattr(info, "workspace_min"):
        lo, hi = np.asarray(info.workspace_min, float), np.asarray(info.workspace_max, float)
        rec.log(
            "world/workspace",
            rr.Boxes3D(mins=[lo], sizes=[hi - lo], colors=[WORKSPACE_COLOR], radii=0.001),
            static=True,
        )


def log_scene(
    rec: Any, rr: Any, cfg: ViewerConfig, model: mujoco.MjModel, data: mujoco.MjData, info: Any
) -> dict[int, str]:
    """Log the static part of an episode to the stream ``rec``; returns the bodies that move
    (body id -> entity path), whose poses the recorder samples."""
    _log_description(rec, rr, model, data, info)
    meshes = body_meshes(model, groups=cfg.geom_groups, max_faces_per_geom=cfg.max_faces_per_geom)
    hulls = (
        body_meshes(model, groups=(COLLISION_GROUP,), max_faces_per_geom=cfg.max_faces_per_geom)
        if cfg.collision_geoms
        else {}
    )
    tracked = {}
    for body in sorted(set(meshes) | set(hulls)):
        path = "world/scene" if body == 0 else body_entity_path(rr, model, info, body)
        if body in meshes:
            rec.log(path, _mesh(rr, meshes[body]), static=True)
        if body in hulls:
            rec.log(f"{path}/collision_geoms", _mesh(rr, hulls[body]), static=True)
        if body == 0:
            continue
        if int(model.body_weldid[body]) == 0:  # welded to the world: one static pose
            pose = rr.Transform3D(translation=data.xpos[body], mat3x3=data.xmat[body].reshape(3, 3))
            rec.log(path, pose, static=True)
        else:
            tracked[body] = path
    return tracked
