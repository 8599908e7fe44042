"""What one observation of the depth cameras returns: the fused cloud and each camera's view."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CameraView:
    """One camera's part of an observation.

    For Rerun: log ``Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3])`` of
    ``T_world_camera`` on the camera entity and ``Pinhole`` with ``camera_xyz=RDF`` (the optical
    frame) and ``K`` with ``cx + 0.5, cy + 0.5`` (Rerun puts integer coordinates at pixel
    corners), then ``DepthImage(depth_m, meter=1.0)``.

    Attributes:
        name: MuJoCo camera name.
        K: (3, 3) intrinsics, pixel centres at integer coordinates (see :mod:`hsqbench.sim.camera`).
        width_px, height_px: image size.
        T_world_camera: (4, 4) *believed* (calibrated) pose of the optical frame (x right, y down,
            z forward) in the world; the cloud was back-projected with it.
        T_world_camera_true: (4, 4) the camera's true pose (equal to the above without a
            calibration error); for diagnostics only.
        depth_m: (H, W) float32 measured planar depth, metres, 0 = invalid (after sensor errors,
            range gating and robot masking); 0 outside ``roi``.
        roi: ``(v0, v1, u0, u1)``: rows ``v0:v1`` and columns ``u0:u1`` were processed (the image
            rectangle of the crop box).
        table_plane: (4,) plane ``(a, b, c, d)`` (unit normal up) the table was removed with.
        n_valid_px: valid pixels in ``depth_m``.
        n_cropped: this camera's points left after the crop, before downsampling.
    """

    name: str
    K: Array
    width_px: int
    height_px: int
    T_world_camera: Array
    T_world_camera_true: Array
    depth_m: NDArray[np.float32]
    roi: tuple[int, int, int, int]
    table_plane: Array
    n_valid_px: int
    n_cropped: int

    @property
    def position(self) -> Array:
        """(3,) believed optical centre in the world, metres."""
        return self.T_world_camera[:3, 3]


@dataclass(frozen=True)
class PerceptionTimings:
    """Wall-clock seconds of one observation, by step: rendering the clean depth images,
    sensor errors, back-projection with cropping, fusion with downsampling, and all of it."""

    render_s: float
    noise_s: float
    cloud_s: float
    downsample_s: float
    total_s: float


@dataclass(frozen=True)
class PerceivedCloud:
    """A fused, cropped, downsampled object cloud and how it was made.

    Attributes:
        points: (N, 3) float64 world points, metres (N may be 0: nothing on the table).
        camera_index: (N,) int64 index into ``cameras`` of each point's main contributor.
        cameras: one :class:`CameraView` per camera, in the order of the scene's cameras.
        support_plane: (4,) the nominal table plane ``(a, b, c, d)``, unit normal up.
        workspace_min, workspace_max: (3,) corners of the crop box, metres.
        sensor_model: the sensor model that produced it.
        voxel_m: downsampling voxel size, metres.
        timings: wall-clock seconds by step.
    """

    points: Array
    camera_index: NDArray[np.int64]
    cameras: tuple[CameraView, ...]
    support_plane: Array
    workspace_min: Array
    workspace_max: Array
    sensor_model: str
    voxel_m: float
    timings: PerceptionTimings

    @property
    def camera_positions(self) -> Array:
        """(C, 3) believed camera centres, metres (``PlanningContext.camera_positions``)."""
        return np.array([c.position for c in self.cameras])
