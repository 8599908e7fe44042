"""What :meth:`RerunRecorder.on_observation
<hsqbench.viz.rerun_recorder.RerunRecorder.on_observation>` logs for each depth camera: its pose,
its ``Pinhole`` (optical frame RDF) and its depth image, at ``world/cameras/<cam>`` (entity paths
in :mod:`hsqbench.viz.rerun_recorder`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Distance of the drawn image plane from the camera, metres (a small frustum in the 3-D view).
IMAGE_PLANE_DISTANCE_M = 0.1


def camera_entity_name(name: str) -> str:
    """Entity name of a camera: the MuJoCo name without a ``cam_`` prefix (``cam_left`` ->
    ``left``)."""
    return name[4:] if name.startswith("cam_") and len(name) > 4 else name


def depth_image(rr: Any, depth_m: NDArray, unit_m: float) -> Any:
    """A ``DepthImage`` of ``depth_m`` (metres, 0 = invalid) stored as uint16 multiples of
    ``unit_m`` (half the bytes of float32), or as float32 if a depth would not fit in 16 bits."""
    depth = np.asarray(depth_m, dtype=np.float32)
    if depth.size and float(depth.max()) < 65535 * unit_m:
        return rr.DepthImage(np.round(depth / unit_m).astype(np.uint16), meter=1.0 / unit_m)
    return rr.DepthImage(depth, meter=1.0)


def log_camera(rec: Any, rr: Any, cam: Any, depth_unit_m: float) -> None:
    """Log one camera of an observation (pose, intrinsics, depth) to the stream ``rec``."""
    path = f"world/cameras/{rr.escape_entity_path_part(camera_entity_name(cam.name))}"
    T = np.asarray(cam.T_world_camera, dtype=np.float64)
    K = np.asarray(cam.K, dtype=np.float64).copy()
    K[0, 2] += 0.5  # Rerun puts integer pixel coordinates at pixel corners
    K[1, 2] += 0.5
    rec.log(path, rr.Transform3D(translation=T[:3, 3], mat3x3=T[:3, :3]))
    rec.log(
        path,
        rr.Pinhole(
            image_from_camera=K,
            resolution=[int(cam.width_px), int(cam.height_px)],
            camera_xyz=rr.ViewCoordinates.RDF,
            image_plane_distance=IMAGE_PLANE_DISTANCE_M,
        ),
    )
    rec.log(f"{path}/depth", depth_image(rr, cam.depth_m, depth_unit_m))
