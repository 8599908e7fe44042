"""Perception: the fused object cloud from the scene's depth cameras (two; one in the
single-camera mode, ``scene.depth_cameras.names: [cam_left]``).

One observation (:meth:`Perception.observe`):

1. **Render** each camera's planar depth offscreen (:mod:`hsqbench.sim.depth_renderer`: one GL
   context per process, ``MUJOCO_GL=egl`` headless). Only the configured geom groups are drawn (visual geometry, not
   the collision hulls) and no sites. Depth outside the camera's operating range is invalid (0).
2. **Sensor errors** (``sensor_model`` in ``configs/perception.yaml``): ``none``; ``tof``
   (range noise, flying pixels, dropout; :mod:`hsqbench.sim.sensor_noise`); ``calibration`` (a
   fixed rigid error per camera, drawn when the :class:`Perception` is made); or both.
3. **Back-project** the valid pixels with the intrinsics ``K`` and move them into the world with
   the *believed* camera pose (the true pose composed with the calibration error, if any);
   see :mod:`hsqbench.sim.camera` for the conventions.
   Only each camera's region of interest (the image rectangle of the crop box) is processed.
4. **Crop** each camera's points to the workspace box (grown by ``workspace_margin_m`` on every
   side but the bottom) and remove the table: every point at most
   ``table_margin_m`` above the support plane goes. With ``refit_table`` the plane is first
   re-fitted to that camera's own points near the nominal table (least squares, trimmed): a
   calibration error of 0.4 deg moves the table by several millimetres at 1 m, more than the
   margin, and a real pipeline finds the table in its own data the same way.
5. **Fuse and downsample**: the cameras' points are concatenated and replaced by voxel centroids
   (``voxel_m``); a voxel's camera index is the camera that contributed most of its points.

Robot links: the harness moves the arm out of view before perceiving; the workspace crop removes
anything outside the box; with ``drop_robot_pixels`` a segmentation render per camera also
removes pixels showing robot geoms (simulator ground truth, so off by default).

All randomness comes from the generators passed in: the calibration errors from the one given to
:class:`Perception` (drawn even when the model is off, so the noise stream does not depend on
it), the depth noise from the one given to :meth:`Perception.observe`.

Settings: :mod:`hsqbench.sim.perception_config`; results: :mod:`hsqbench.sim.perceived`; crop and
fusion: :mod:`hsqbench.sim.table_crop`.

Use (one :class:`Perception` per compiled scene; renderers are reused across observations)::

    rng = np.random.default_rng(trial_seed)
    with Perception.from_scene(model, info, rng=rng) as perception:
        cloud = perception.observe(data, rng)   # the arm at home, data forward-consistent
    context = PlanningContext(support_plane=tuple(cloud.support_plane),
                              camera_positions=cloud.camera_positions,
                              workspace_bounds=(cloud.workspace_min, cloud.workspace_max))
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import validate_plane
from hsqbench.sim.camera import (
    backproject,
    box_roi,
    camera_intrinsics,
    camera_pose,
    crop_intrinsics,
    transform_points,
)
from hsqbench.sim.depth_renderer import DepthRenderer
from hsqbench.sim.perceived import CameraView, PerceivedCloud, PerceptionTimings
from hsqbench.sim.perception_config import (
    SENSOR_MODELS,
    CropConfig,
    PerceptionConfig,
    SensorModel,
    load_perception_config,
)
from hsqbench.sim.sensor_noise import apply_dex_noise, apply_tof_noise, calibration_errors
from hsqbench.sim.table_crop import (
    fit_plane,
    fuse_and_downsample,
    refit_table_plane,
    workspace_mask,
)

if TYPE_CHECKING:
    from hsqbench.sim.scene import DepthCamera, SceneInfo

__all__ = [
    "ROI_PAD_PX",
    "SENSOR_MODELS",
    "CameraView",
    "CropConfig",
    "PerceivedCloud",
    "Perception",
    "PerceptionConfig",
    "PerceptionTimings",
    "SensorModel",
    "fit_plane",
    "fuse_and_downsample",
    "load_perception_config",
    "refit_table_plane",
    "workspace_mask",
]

Array = NDArray[np.float64]
#: Pixels added around the crop box's image rectangle: the noise model's 3 x 3 neighbourhoods
#: and central differences need one, and one more absorbs rounding.
ROI_PAD_PX = 2


# ---- the sensor --------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Camera:
    name: str
    cam_id: int
    K: Array
    width_px: int
    height_px: int
    min_range_m: float
    max_range_m: float


class Perception:
    """The scene's depth cameras, rendering through renderers made once per model.

    Create one per compiled model (renderers are bound to a model) and reuse it for every
    observation of that scene; call :meth:`close` (or use ``with``) to free the GL resources.

    Args:
        model: the compiled scene.
        cameras: the depth cameras (``SceneInfo.depth_cameras``: ``name``, ``min_range_m``,
            ``max_range_m``; image size and field of view come from the model and must agree
            with ``width_px``/``height_px``/``fovy_deg`` where those are given).
        support_plane: (4,) nominal table plane ``(a, b, c, d)``, normal up.
        workspace_min, workspace_max: (3,) corners of the region objects may occupy, metres.
        config: perception settings; ``None`` loads ``configs/perception.yaml``.
        rng: draws the per-camera calibration errors.
        robot_geom_ids: geoms dropped by segmentation when ``config.drop_robot_pixels``.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        cameras: Sequence[DepthCamera],
        *,
        support_plane: ArrayLike,
        workspace_min: ArrayLike,
        workspace_max: ArrayLike,
        rng: np.random.Generator,
        config: PerceptionConfig | None = None,
        robot_geom_ids: ArrayLike | None = None,
    ) -> None:
        self.config = config if config is not None else load_perception_config()
        self.model = model
        if not cameras:
            raise ValueError("Perception needs at least one depth camera")
        self.support_plane = validate_plane(support_plane)
        self.workspace_min = np.asarray(workspace_min, dtype=np.float64).reshape(3)
        self.workspace_max = np.asarray(workspace_max, dtype=np.float64).reshape(3)
        if not np.all(self.workspace_min < self.workspace_max):
            raise ValueError(
                f"workspace_min {self.workspace_min} must lie below workspace_max "
                f"{self.workspace_max} on every axis"
            )
        self._cameras = tuple(self._resolve(model, c) for c in cameras)
        errors = calibration_errors(len(self._cameras), self.config.calibration, rng)
        #: (C, 4, 4) calibration error of each camera: believed pose = true pose @ error.
        self.camera_errors = (
            errors if self.config.calibration_on else np.tile(np.eye(4), (len(errors), 1, 1))
        )
        self._robot_geoms = np.unique(
            np.asarray(robot_geom_ids if robot_geom_ids is not None else [], dtype=np.int64)
        )
        if self.config.drop_robot_pixels and robot_geom_ids is None:
            raise ValueError(
                "drop_robot_pixels needs robot_geom_ids (Perception.from_scene finds them)"
            )

        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = 0
        self._option.geomgroup[list(self.config.geom_groups)] = 1
        self._option.sitegroup[:] = 0
        self._renderers: dict[tuple[int, int], DepthRenderer] = {}
        try:
            for cam in self._cameras:
                size = (cam.height_px, cam.width_px)
                if size not in self._renderers:
                    self._renderers[size] = DepthRenderer(model, *size)
        except Exception:
            self.close()
            raise

    @classmethod
    def from_scene(
        cls,
        model: mujoco.MjModel,
        info: SceneInfo,
        *,
        rng: np.random.Generator,
        config: PerceptionConfig | None = None,
    ) -> Perception:
        """A :class:`Perception` for a scene of :func:`hsqbench.sim.scene.build_scene`."""
        prefix = info.robot_prefix
        robot_bodies = [
            b
            for b in range(model.nbody)
            if (mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "").startswith(prefix)
        ]
        robot_geoms = np.flatnonzero(np.isin(model.geom_bodyid, robot_bodies))
        return cls(
            model,
            info.depth_cameras,
            support_plane=info.support_plane,
            workspace_min=info.workspace_min,
            workspace_max=info.workspace_max,
            rng=rng,
            config=config,
            robot_geom_ids=robot_geoms,
        )

    @staticmethod
    def _resolve(model: mujoco.MjModel, cam: DepthCamera) -> _Camera:
        cam_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, cam.name)
        if cam_id < 0:
            known = [
                mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_CAMERA, i) for i in range(model.ncam)
            ]
            raise ValueError(f"no camera {cam.name!r} in the model; cameras: {known}")
        K, width, height = camera_intrinsics(model, cam_id)
        expected = {
            "width_px": width,
            "height_px": height,
            "fovy_deg": float(model.cam_fovy[cam_id]),
        }
        for attr, value in expected.items():
            given = getattr(cam, attr, None)
            if given is not None and not np.isclose(given, value):
                raise ValueError(
                    f"camera {cam.name!r}: {attr} = {given} in its description but {value} in "
                    "the model; rebuild the scene from one config"
                )
        if not 0.0 <= cam.min_range_m < cam.max_range_m:
            raise ValueError(
                f"camera {cam.name!r}: need 0 <= min_range_m < max_range_m, got "
                f"{cam.min_range_m}, {cam.max_range_m}"
            )
        return _Camera(cam.name, cam_id, K, width, height, cam.min_range_m, cam.max_range_m)

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self._cameras)

    def close(self) -> None:
        """Free the renderers (idempotent)."""
        for renderer in self._renderers.values():
            renderer.close()
        self._renderers = {}

    def __enter__(self) -> Perception:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _renderer(self, cam: _Camera) -> DepthRenderer:
        if not self._renderers:
            raise RuntimeError("this Perception is closed; make a new one")
        return self._renderers[(cam.height_px, cam.width_px)]

    def render_depth(self, data: mujoco.MjData) -> list[NDArray[np.float32]]:
        """Clean planar depth (H, W) of every camera, metres, 0 outside the operating range
        (and on robot pixels with ``drop_robot_pixels``). ``data`` must be forward-consistent
        (after ``mj_forward`` or ``mj_step``)."""
        images = []
        for cam in self._cameras:
            renderer = self._renderer(cam)
            depth = renderer.depth(data, cam.cam_id, self._option)
            depth[(depth < cam.min_range_m) | (depth > cam.max_range_m)] = 0.0
            if self.config.drop_robot_pixels:
                seg = renderer.segmentation(data, cam.cam_id, self._option)
                robot = (seg[..., 1] == mujoco.mjtObj.mjOBJ_GEOM) & np.isin(
                    seg[..., 0], self._robot_geoms
                )
                depth[robot] = 0.0
            images.append(depth)
        return images

    def _camera_cloud(
        self,
        cam: _Camera,
        pose: Array,
        true_pose: Array,
        full: NDArray[np.float32],
        depth: NDArray[np.float32],
        roi: tuple[int, int, int, int],
        K_roi: Array,
    ) -> tuple[Array, CameraView]:
        """Steps 3-4 for one camera: its region-of-interest ``depth`` (sensor errors applied)
        back-projected with the believed ``pose``, cropped to the workspace and cleared of the
        table; returns those points and the camera's :class:`CameraView` (``full`` gives the
        image size of its ``depth_m``)."""
        cfg = self.config
        v0, v1, u0, u1 = roi
        measured = np.zeros_like(full)
        measured[v0:v1, u0:u1] = depth
        valid = depth > 0
        points = transform_points(pose, backproject(depth, K_roi)[valid])
        margin = cfg.crop.workspace_margin_m
        points = points[workspace_mask(points, self.workspace_min, self.workspace_max, margin)]
        plane = (
            refit_table_plane(points, self.support_plane, cfg.crop)
            if cfg.crop.refit_table
            else self.support_plane
        )
        points = points[points @ plane[:3] + plane[3] > cfg.crop.table_margin_m]
        view = CameraView(
            name=cam.name,
            K=cam.K.copy(),
            width_px=cam.width_px,
            height_px=cam.height_px,
            T_world_camera=pose,
            T_world_camera_true=true_pose,
            depth_m=measured,
            roi=roi,
            table_plane=plane,
            n_valid_px=int(valid.sum()),
            n_cropped=len(points),
        )
        return points, view

    def observe(self, data: mujoco.MjData, rng: np.random.Generator) -> PerceivedCloud:
        """One fused observation of the scene in ``data`` (see the module docstring).

        Only each camera's region of interest (the image rectangle of the crop box, padded by
        :data:`ROI_PAD_PX`) is processed: sensor errors, back-projection and cropping there;
        ``CameraView.depth_m`` is 0 outside it.

        Args:
            data: the simulation state, forward-consistent; the arm should be out of view.
            rng: draws the depth noise (unused with sensor models without ``tof``).
        """
        cfg = self.config
        t0 = time.perf_counter()
        clean = self.render_depth(data)
        t_render = time.perf_counter() - t0
        margin = cfg.crop.workspace_margin_m
        below = max(cfg.crop.refit_band_m, cfg.crop.table_margin_m)
        box_lo = self.workspace_min - np.array([margin, margin, below])
        box_hi = self.workspace_max + margin
        t_noise = t_cloud = 0.0
        views, clouds = [], []
        for i, (cam, full) in enumerate(zip(self._cameras, clean, strict=True)):
            t = time.perf_counter()
            true_pose = camera_pose(data, cam.cam_id)
            pose = true_pose @ self.camera_errors[i]
            roi = box_roi(pose, cam.K, cam.width_px, cam.height_px, box_lo, box_hi, ROI_PAD_PX)
            v0, v1, u0, u1 = roi
            K_roi = crop_intrinsics(cam.K, v0, u0)
            if cfg.dex_on:  # whole-image noise (one factor and one warp per image)
                full = apply_dex_noise(full, cfg.dex, rng)
            depth = full[v0:v1, u0:u1]
            if cfg.tof_on:
                depth = apply_tof_noise(depth, K_roi, cfg.tof, rng).depth_m
            t_noise += time.perf_counter() - t
            t = time.perf_counter()
            points, view = self._camera_cloud(cam, pose, true_pose, full, depth, roi, K_roi)
            clouds.append(points)
            views.append(view)
            t_cloud += time.perf_counter() - t
        t = time.perf_counter()
        fused, camera_index = fuse_and_downsample(clouds, cfg.voxel_m)
        t_down = time.perf_counter() - t
        return PerceivedCloud(
            points=fused,
            camera_index=camera_index,
            cameras=tuple(views),
            support_plane=self.support_plane.copy(),
            workspace_min=self.workspace_min.copy(),
            workspace_max=self.workspace_max.copy(),
            sensor_model=cfg.sensor_model,
            voxel_m=cfg.voxel_m,
            timings=PerceptionTimings(t_render, t_noise, t_cloud, t_down, time.perf_counter() - t0),
        )
