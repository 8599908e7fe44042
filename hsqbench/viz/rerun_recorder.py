"""Record a trial or packed round to a Rerun ``.rrd`` file (the episode viewer).

:class:`RerunRecorder` implements :class:`hsqbench.sim.recorder.Recorder`. Everything is in the
world frame (the robot base frame: z up, metres) on one timeline, ``sim_time`` (simulated
seconds, ``MjData.time``). Entity paths:

- ``world``: view coordinates, right-handed, z up (static).
- ``world/scene``: table, legs and bin as one mesh (static).
- ``world/workspace``: the placement / crop box, wireframe (static).
- ``world/robot/<body>``: each Panda link's mesh in the body frame (static) and its pose
  (``Transform3D``) every ``step_interval_s``; ``world/objects/<name>``: each object, the same.
- ``world/<...>/collision_geoms``: collision geoms, if ``collision_geoms`` (left out of the
  default 3-D view).
- ``world/cameras/<cam>``: camera pose and ``Pinhole`` (optical frame RDF) at each observation;
  ``<cam>`` is the MuJoCo camera name without ``cam_``. ``world/cameras/<cam>/depth``: the
  measured depth image (0 = invalid).
- ``world/cloud``: the fused, cropped cloud, coloured by camera.
- ``world/planner/superquadrics/<i>``: hidden superquadric ``i`` as a mesh coloured by the score
  of its best grasp (grey: none), with its parameters as values; ``.../<i>/inliers``: the
  points it explains (at most ``max_inliers``, evenly subsampled), in the same colour.
- ``world/planner/candidates/<class>``: candidates as arrows along the approach axis ending at
  P_G; ``kept`` coloured by score, the others by the rule that removed them (``width``,
  ``duplicate``, ``width``, ``support``, ``table``, ``collision``, ``sweep``).
- ``world/planner/surface``: a planner's own surface (vgn and giga: the TSDF's zero crossings).
- ``world/planner/top_grasps``: outlines of the best ``top_grasps`` grasps;
  ``world/planner/chosen_grasp``: the outline of the executed one (white).
- ``plots/gripper_width``: finger opening over time, metres.
- ``events``: text log of perception, planning, phases and outcomes; ``outcome``: the attempt's
  outcome as a text document; ``scene``: what was simulated (static).

When each is logged: the scene and the initial poses in ``on_scene``; cameras, depth and cloud in
``on_observation``; superquadrics, candidates and top grasps in ``on_plan``; the chosen grasp in
``on_grasp``; poses and the gripper width are buffered in ``on_step`` (a copy of a few arrays)
and sent as columns in ``on_outcome`` and :meth:`RerunRecorder.close`, so stepping stays cheap.
In a packed round the planner's entities are cleared at each new observation.

Off is free: the trial runner never calls a recorder whose ``enabled`` is False, and this module
(and ``rerun``) is only imported when ``--rerun`` asks for a recording.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.viz.blueprint import episode_blueprint
from hsqbench.viz.colors import camera_colors
from hsqbench.viz.config import ViewerConfig, load_viewer_config
from hsqbench.viz.gripper_outline import gripper_outline
from hsqbench.viz.rerun_plan import (
    _best_scores,
    _log_plan_geometry,
    _log_superquadrics,
    _log_top_grasps,
)
from hsqbench.viz.scene_geometry import BodyMesh, body_meshes

TIMELINE = "sim_time"
CHOSEN_COLOR = (255, 255, 255, 255)
WORKSPACE_COLOR = (200, 200, 200, 255)
CLOUD_COLOR = (230, 230, 230, 255)


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


def camera_entity_name(name: str) -> str:
    """Entity name of a camera: the MuJoCo name without a ``cam_`` prefix (``cam_left`` ->
    ``left``)."""
    return name[4:] if name.startswith("cam_") and len(name) > 4 else name


def _part(name: str) -> str:
    import rerun as rr

    return rr.escape_entity_path_part(name)


def depth_image(rr: Any, depth_m: NDArray, unit_m: float) -> Any:
    """A ``DepthImage`` of ``depth_m`` (metres, 0 = invalid) stored as uint16 multiples of
    ``unit_m`` (half the bytes of float32), or as float32 if a depth would not fit in 16 bits."""
    depth = np.asarray(depth_m, dtype=np.float32)
    if depth.size and float(depth.max()) < 65535 * unit_m:
        return rr.DepthImage(np.round(depth / unit_m).astype(np.uint16), meter=1.0 / unit_m)
    return rr.DepthImage(depth, meter=1.0)


class RerunRecorder:
    """Writes one episode (a trial or a packed round) to ``path`` (see the module docstring).

    Use as a context manager, or call :meth:`close` at the end (it sends the buffered poses and
    closes the file)::

        with RerunRecorder("episode.rrd") as rec:
            run_isolated_trial("proc_box", 0, recorder=rec)

    Args:
        path: output ``.rrd`` file (its directory is created).
        config: logging settings; default ``configs/viewer.yaml``.
        gripper: drawn for grasps; default the planner's gripper (``configs/gripper.yaml``).
        application_id: Rerun application id (the viewer groups recordings by it).
    """

    enabled = True

    def __init__(
        self,
        path: str | Path,
        config: ViewerConfig | None = None,
        *,
        gripper: Any = None,
        application_id: str = "hsqbench",
    ) -> None:
        import rerun as rr

        self.path = Path(path)
        if self.path.suffix != ".rrd":
            raise ValueError(f"a Rerun recording must end in .rrd, got {str(path)!r}")
        self.config = config if config is not None else load_viewer_config()
        self.step_interval_s = float(self.config.step_interval_s)
        if gripper is None:
            from hsqbench.planner.gripper import resolve_gripper
            from hsqbench.planner.hsq.config import resolve_config

            gripper = resolve_gripper(resolve_config(None).grasp.gripper)
        self.gripper = gripper
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._rr = rr
        self.rec = rr.RecordingStream(application_id)
        self.rec.save(self.path)
        self._data: mujoco.MjData | None = None
        self._cloud: NDArray[np.float64] | None = None
        self._tracked: dict[int, str] = {}
        self._finger_adr = np.zeros(0, dtype=np.int64)
        self._times: list[float] = []
        self._pos: list[NDArray[np.float64]] = []
        self._mat: list[NDArray[np.float64]] = []
        self._width: list[float] = []
        self._phase = ""
        self._attempt = 0
        self._closed = False

    # ---- helpers -------------------------------------------------------------------------------
    def _now(self) -> float:
        return float(self._data.time) if self._data is not None else 0.0

    def _at_now(self) -> float:
        t = self._now()
        self.rec.set_time(TIMELINE, duration=t)
        return t

    def _event(self, text: str, level: str = "INFO") -> None:
        self.rec.log("events", self._rr.TextLog(text, level=level))

    def _body_path(self, model: mujoco.MjModel, info: Any, body: int) -> str:
        name = model.body(body).name
        objects = {int(v): k for k, v in getattr(info, "object_body_ids", {}).items()}
        if body in objects:
            return f"world/objects/{_part(objects[body])}"
        prefix = getattr(info, "robot_prefix", "")
        if prefix and name.startswith(prefix):
            return f"world/robot/{_part(name[len(prefix) :])}"
        return f"world/bodies/{_part(name or str(body))}"

    def _mesh(self, mesh: BodyMesh) -> Any:
        return self._rr.Mesh3D(
            vertex_positions=mesh.vertices,
            triangle_indices=mesh.faces,
            vertex_colors=mesh.colors,
            vertex_normals=mesh.normals,
        )

    # ---- Recorder protocol ---------------------------------------------------------------------
    def on_scene(self, model: mujoco.MjModel, data: mujoco.MjData, info: Any) -> None:
        """Static geometry, the initial poses and a description of the scene."""
        rr, cfg = self._rr, self.config
        self._data = data
        kind, objects = getattr(info, "kind", "?"), list(getattr(info, "objects", []))
        seed = getattr(info, "seed", "?")
        self.rec.send_recording_name(f"{kind} {' '.join(objects)} seed {seed}")
        self.rec.send_blueprint(_layout(model, data, info))
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        self.rec.log(
            "scene",
            rr.TextDocument(
                f"**{kind}** scene, seed {seed}\n\nobjects: {', '.join(objects) or '-'}",
                media_type=rr.MediaType.MARKDOWN,
            ),
            static=True,
        )
        if hasattr(info, "workspace_min"):
            lo, hi = np.asarray(info.workspace_min, float), np.asarray(info.workspace_max, float)
            self.rec.log(
                "world/workspace",
                rr.Boxes3D(mins=[lo], sizes=[hi - lo], colors=[WORKSPACE_COLOR], radii=0.001),
                static=True,
            )

        meshes = body_meshes(
            model, groups=cfg.geom_groups, max_faces_per_geom=cfg.max_faces_per_geom
        )
        hulls = (
            body_meshes(model, groups=(3,), max_faces_per_geom=cfg.max_faces_per_geom)
            if cfg.collision_geoms
            else {}
        )
        for body in sorted(set(meshes) | set(hulls)):
            path = "world/scene" if body == 0 else self._body_path(model, info, body)
            if body in meshes:
                self.rec.log(path, self._mesh(meshes[body]), static=True)
            if body in hulls:
                self.rec.log(f"{path}/collision_geoms", self._mesh(hulls[body]), static=True)
            if body == 0:
                continue
            if int(model.body_weldid[body]) == 0:  # welded to the world: one static pose
                self.rec.log(
                    path,
                    rr.Transform3D(
                        translation=data.xpos[body], mat3x3=data.xmat[body].reshape(3, 3)
                    ),
                    static=True,
                )
            else:
                self._tracked[body] = path
        fingers = [model.joint(n).id for n in getattr(info, "finger_joints", ())]
        self._finger_adr = np.asarray(model.jnt_qposadr[fingers], dtype=np.int64)
        self._at_now()
        self._event(f"scene: {kind}, seed {seed}, objects {', '.join(objects) or '-'}")
        self._sample(data)

    def on_observation(self, observation: Any) -> None:
        """Cameras (pose, intrinsics, depth) and the fused cloud."""
        rr, cfg = self._rr, self.config
        self._at_now()
        self._attempt += 1
        if self._attempt > 1:
            self.rec.log("world/planner", rr.Clear(recursive=True))
        points = np.asarray(observation.points, dtype=np.float64).reshape(-1, 3)
        self._cloud = points
        cams = getattr(observation, "cameras", None)
        if cams is not None and hasattr(observation, "camera_index"):
            colors = camera_colors(observation.camera_index)
        else:
            colors = np.broadcast_to(np.array(CLOUD_COLOR, np.uint8), (len(points), 4))
        self.rec.log("world/cloud", rr.Points3D(points, colors=colors, radii=cfg.cloud_radius_m))
        if cams is not None:
            for cam in cams:
                self._log_camera(cam)
        else:
            positions = np.asarray(getattr(observation, "camera_positions", np.zeros((0, 3))))
            self.rec.log(
                "world/cameras",
                rr.Points3D(positions.reshape(-1, 3), radii=0.02, labels=None),
            )
        self._event(f"attempt {self._attempt}: perceived {len(points)} points")

    def _log_camera(self, cam: Any) -> None:
        rr = self._rr
        path = f"world/cameras/{_part(camera_entity_name(cam.name))}"
        T = np.asarray(cam.T_world_camera, dtype=np.float64)
        K = np.asarray(cam.K, dtype=np.float64).copy()
        K[0, 2] += 0.5  # Rerun puts integer pixel coordinates at pixel corners
        K[1, 2] += 0.5
        self.rec.log(path, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
        self.rec.log(
            path,
            rr.Pinhole(
                image_from_camera=K,
                resolution=[int(cam.width_px), int(cam.height_px)],
                camera_xyz=rr.ViewCoordinates.RDF,
                image_plane_distance=0.1,
            ),
        )
        self.rec.log(f"{path}/depth", depth_image(self._rr, cam.depth_m, self.config.depth_unit_m))

    def on_plan(self, plan: Any) -> None:
        """Hidden superquadrics, candidates by fate, and the best grasps."""
        rr, cfg = self._rr, self.config
        self._at_now()
        hidden = list(getattr(plan, "hidden_superquadrics", []) or [])
        best = _best_scores(plan, len(hidden))
        _log_superquadrics(self.rec, rr, cfg, hidden, best, self._cloud)
        _log_plan_geometry(self.rec, rr, cfg, plan)
        grasps = plan.grasps
        _log_top_grasps(self.rec, rr, cfg, self.gripper, grasps)
        removed = ", ".join(f"{k} {v}" for k, v in getattr(plan, "removed_by", {}).items() if v)
        total = getattr(plan, "timings", {}).get("total")
        took = f" in {total:.2f} s" if total is not None else ""
        reason = getattr(plan, "reason", "")
        self._event(
            f"planned{took}: {len(grasps)} grasps from {len(hidden)} hidden superquadrics"
            + (f"; removed {removed}" if removed else "")
            + (f"; {reason}" if reason else ""),
            level="INFO" if len(grasps) else "WARN",
        )

    def on_grasp(self, grasp: Any, rank: int) -> None:
        """The grasp about to be executed, as a gripper outline."""
        rr, cfg = self._rr, self.config
        self._at_now()
        lines = gripper_outline(
            self.gripper, grasp.position, grasp.rotation, grasp.width, cfg.stem_length_m
        )
        self.rec.log(
            "world/planner/chosen_grasp",
            rr.LineStrips3D(
                lines,
                colors=[CHOSEN_COLOR] * len(lines),
                labels=[f"rank {rank}, score {grasp.score:.3f}"] + [""] * (len(lines) - 1),
                radii=cfg.outline_radius_m,
            ),
        )
        self._event(
            f"executing rank {rank}: score {grasp.score:.3f}, width {grasp.width * 1000:.0f} mm"
        )

    def on_step(self, model: mujoco.MjModel, data: mujoco.MjData, phase: str) -> None:
        """Buffer the moving bodies' poses (sent in columns later)."""
        if phase != self._phase:
            self._phase = phase
            self._at_now()
            self._event(f"phase: {phase}")
        self._sample(data)

    def _sample(self, data: mujoco.MjData) -> None:
        ids = np.fromiter(self._tracked, dtype=np.int64, count=len(self._tracked))
        self._times.append(float(data.time))
        self._pos.append(data.xpos[ids].copy())
        self._mat.append(data.xmat[ids].copy())
        self._width.append(float(data.qpos[self._finger_adr].sum()))

    def on_outcome(self, attempt: Any) -> None:
        """The outcome as text; sends the buffered poses."""
        rr = self._rr
        if self._data is not None:
            self._sample(self._data)
        self._at_now()
        outcome = str(getattr(attempt, "outcome", "?"))
        lines = [f"## attempt {self._attempt}: {outcome}", ""]
        for key in ("target", "rank_executed", "n_grasps", "score", "width_m", "detail"):
            value = getattr(attempt, key, None)
            if value is not None and value != "":
                lines.append(
                    f"- {key}: {value:.4g}" if isinstance(value, float) else f"- {key}: {value}"
                )
        factors = getattr(attempt, "factors", {}) or {}
        if factors:
            lines.append("- factors: " + ", ".join(f"{k} {v:.3f}" for k, v in factors.items()))
        for key in ("perception_s", "planning_s", "execution_s"):
            lines.append(f"- {key}: {float(getattr(attempt, key, np.nan)):.2f}")
        self.rec.log("outcome", rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN))
        ok = getattr(attempt, "success", False)
        detail = getattr(attempt, "detail", "")
        self._event(
            f"outcome: {outcome}" + (f" ({detail})" if detail else ""),
            level="INFO" if ok else "WARN",
        )
        self._flush_poses()

    # ---- output --------------------------------------------------------------------------------
    def _flush_poses(self) -> None:
        if not self._times:
            return
        rr = self._rr
        times = np.asarray(self._times)
        # Samples at equal times (the scene's initial pose and a first step) keep the last one.
        keep = np.r_[np.diff(times) > 0, True]
        times = times[keep]
        index = [rr.TimeColumn(TIMELINE, duration=times)]
        pos = np.asarray(self._pos)[keep]
        mat = np.asarray(self._mat)[keep].reshape(len(times), -1, 3, 3)
        for k, path in enumerate(self._tracked.values()):
            self.rec.send_columns(
                path, index, rr.Transform3D.columns(translation=pos[:, k], mat3x3=mat[:, k])
            )
        if self._finger_adr.size:
            self.rec.send_columns(
                "plots/gripper_width",
                index,
                rr.Scalars.columns(scalars=np.asarray(self._width)[keep]),
            )
        self._times, self._pos, self._mat, self._width = [], [], [], []

    def close(self) -> None:
        """Send what is buffered and close the file (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._flush_poses()
        self.rec.flush()
        self.rec.disconnect()

    def __enter__(self) -> RerunRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
