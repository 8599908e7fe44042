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
In a packed round the planner's entities are cleared at each new observation. What each hook logs
lives beside this module: the scene in :mod:`~hsqbench.viz.rerun_scene`, each camera in
:mod:`~hsqbench.viz.rerun_cameras`, the plan in :mod:`~hsqbench.viz.rerun_plan`.

Off is free: the trial runner never calls a recorder whose ``enabled`` is False, and this module
(and ``rerun``) is only imported when ``--rerun`` asks for a recording.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.viz.colors import camera_colors
from hsqbench.viz.config import ViewerConfig, load_viewer_config
from hsqbench.viz.gripper_outline import gripper_outline
from hsqbench.viz.rerun_cameras import log_camera
from hsqbench.viz.rerun_plan import (
    _best_scores,
    _log_plan_geometry,
    _log_superquadrics,
    _log_top_grasps,
)
from hsqbench.viz.rerun_scene import log_scene

TIMELINE = "sim_time"
CHOSEN_COLOR = (255, 255, 255, 255)
CLOUD_COLOR = (230, 230, 230, 255)


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

    # ---- Recorder protocol ---------------------------------------------------------------------
    def on_scene(self, model: mujoco.MjModel, data: mujoco.MjData, info: Any) -> None:
        """Static geometry, the initial poses and a description of the scene."""
        self._data = data
        self._tracked.update(log_scene(self.rec, self._rr, self.config, model, data, info))
        fingers = [model.joint(n).id for n in getattr(info, "finger_joints", ())]
        self._finger_adr = np.asarray(model.jnt_qposadr[fingers], dtype=np.int64)
        self._at_now()
        kind, objects = getattr(info, "kind", "?"), list(getattr(info, "objects", []))
        seed = getattr(info, "seed", "?")
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
                log_camera(self.rec, rr, cam, cfg.depth_unit_m)
        else:
            positions = np.asarray(getattr(observation, "camera_positions", np.zeros((0, 3))))
            self.rec.log(
                "world/cameras",
                rr.Points3D(positions.reshape(-1, 3), radii=0.02, labels=None),
            )
        self._event(f"attempt {self._attempt}: perceived {len(points)} points")

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
