"""A fast stand-in for the depth cameras: points sampled on the objects' visible surfaces.

For tests and quick runs without OpenGL (``sensor: surface`` in ``configs/trial.yaml``); the
benchmark uses :mod:`hsqbench.sim.perception` (rendered depth from the two cameras).

Each object's visual mesh (the real surface; the collision hulls would add interior faces where
hulls meet) is sampled area-uniformly at about one point per ``spacing_m`` squared, moved to the
object's current pose, and a point is kept when its face looks toward at least one camera
(back-face culling: no occlusion by other objects or by the object's own concave parts) and it
lies more than ``table_margin_m`` above the table inside the workspace box grown by
``workspace_margin_m``. Isotropic Gaussian noise of ``noise_m`` is added. Everything random comes
from the generator passed to :meth:`SurfaceSensor.observe`.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.objects import ObjectLike


@dataclass(frozen=True)
class SurfaceSensorConfig:
    """Settings of :class:`SurfaceSensor` (lengths in metres; reasons in ``configs/trial.yaml``)."""

    spacing_m: float = 0.003
    noise_m: float = 0.001
    table_margin_m: float = 0.005
    workspace_margin_m: float = 0.02

    def __post_init__(self) -> None:
        if not self.spacing_m > 0 or self.noise_m < 0:
            raise ValueError("surface sensor: spacing_m must be > 0 and noise_m >= 0")


@dataclass(frozen=True)
class SurfaceCloud:
    """The stand-in's observation: ``points`` (N, 3) world metres, the cameras' centres
    ``camera_positions`` (C, 3), and the wall-clock seconds it took."""

    points: NDArray[np.float64]
    camera_positions: NDArray[np.float64]
    total_s: float


@cache
def _mesh(path: Path) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Triangles (F, 3, 3), unit normals (F, 3) and areas (F,) of a mesh file."""
    import trimesh

    mesh = trimesh.load(path, force="mesh")
    return mesh.triangles.copy(), mesh.face_normals.copy(), mesh.area_faces.copy()


class SurfaceSensor:
    """Samples visible object surfaces (see the module docstring).

    Args:
        objects: object name -> its asset (for the visual mesh).
        body_ids: object name -> body id in the model.
        camera_ids: ids of the depth cameras in the model.
        workspace_min, workspace_max: (3,) crop box corners, metres; z from the table top.
        table_z: height of the table top, metres.
    """

    def __init__(
        self,
        objects: Mapping[str, ObjectLike],
        body_ids: Mapping[str, int],
        camera_ids: list[int],
        workspace_min: NDArray[np.float64],
        workspace_max: NDArray[np.float64],
        table_z: float,
        config: SurfaceSensorConfig,
    ) -> None:
        self.objects = dict(objects)
        self.body_ids = dict(body_ids)
        self.camera_ids = list(camera_ids)
        self.config = config
        m = config.workspace_margin_m
        self.lo = np.asarray(workspace_min, float) - np.array([m, m, 0.0])
        self.lo[2] = table_z + config.table_margin_m
        self.hi = np.asarray(workspace_max, float) + m

    def observe(self, data: mujoco.MjData, rng: np.random.Generator) -> SurfaceCloud:
        t0 = time.perf_counter()
        cams = data.cam_xpos[self.camera_ids].copy()
        clouds = []
        for name, asset in self.objects.items():
            b = self.body_ids[name]
            tris, normals, areas = _mesh(Path(asset.visual_mesh))
            n = max(1, int(areas.sum() / self.config.spacing_m**2))
            face = rng.choice(len(areas), size=n, p=areas / areas.sum())
            r1, r2 = rng.random(n), rng.random(n)
            flip = r1 + r2 > 1.0
            r1[flip], r2[flip] = 1.0 - r1[flip], 1.0 - r2[flip]
            t = tris[face]
            local = t[:, 0] + r1[:, None] * (t[:, 1] - t[:, 0]) + r2[:, None] * (t[:, 2] - t[:, 0])
            rot = data.xmat[b].reshape(3, 3)
            pts = local @ rot.T + data.xpos[b]
            nrm = normals[face] @ rot.T
            seen = np.zeros(n, dtype=bool)
            for c in cams:
                seen |= np.einsum("ij,ij->i", nrm, c - pts) > 0
            clouds.append(pts[seen])
        pts = np.concatenate(clouds) if clouds else np.zeros((0, 3))
        if self.config.noise_m > 0 and len(pts):
            pts = pts + rng.normal(0.0, self.config.noise_m, size=pts.shape)
        keep = np.all((pts >= self.lo) & (pts <= self.hi), axis=1)
        return SurfaceCloud(pts[keep], cams, time.perf_counter() - t0)
