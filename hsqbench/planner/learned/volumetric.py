"""The ``vgn`` and ``giga`` planners: VGN and GIGA with their published weights, in the harness.

Per observation (:meth:`VolumetricPlanner.stages`):

0. **Inputs** (``input``). The published weights were trained on the TSDF of one depth image
   taken from the cube's -y side (:func:`input_frames`). ``per_view`` (default): each camera is
   one input, in a frame yawed about the vertical so that the camera lies on the -y side of the
   cloud's footprint centre (:func:`view_yaw`; the networks know the table and gravity, not the
   world's yaw), integrated from that camera's image alone; ``fused``: one input, the world
   axes, every image.
1. **Cubes.** The networks see one 0.30 m cube (40^3 voxels of 7.5 mm) with the table 5 cm above
   its floor; the workspace is wider. Cubes, axis-aligned with the input's frame, are tiled over
   the footprint of the (cleaned) cloud so that the part of each cube where grasps are kept
   (inside the detection's x/y bounds) covers it: one cube for an isolated object, up to
   ``max_cubes_per_axis`` per axis for a packed scene (:func:`cube_origins`).
2. **TSDF.** Each cube's TSDF is integrated from the input's depth images, the same noisy images
   the cloud of every other planner comes from (``PlanningContext.depth_views``; :mod:`.tsdf`),
   or (``viewpoint: training``) from each re-projected into the training camera of the cube
   (:mod:`.viewpoint`).
3. **Network.** All cubes of all inputs in one batch: VGN's volumes, or GIGA's encoder and its
   decoders at the voxels the detection reads (:mod:`.vgn_net`, :mod:`.giga_net`).
4. **Detection** as the papers do it (:mod:`.detection`); a grasp in the overlap of two cubes of
   one input is kept only from the cube whose kept part is centred nearest to it, so no grasp
   comes twice from one input. The inputs' grasps, mapped back to the world, are merged
   (``merge: best``: all of them, ranked by their own quality).

Grasps: the network's position (voxel index times voxel size, the networks' convention) is its
hand's TCP; ``P_G`` lies ``pads_beyond_tcp_m`` further along the approach (the config says why);
the orientation's y axis is the closing and z the approach axis; width as predicted.
Scores are the smoothed quality. The weights follow the scene kind
(``PlanningContext.scene``): packed weights in isolated and packed scenes, pile weights in piles.
Nothing is random: the same observation gives the same grasps whatever the seed.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.api import PlanningContext, PlanResult, validate_plane
from hsqbench.planner.base import CleanInput, PlannerBase
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.hsq.config import resolve_config
from hsqbench.planner.learned import detection, tsdf, viewpoint
from hsqbench.planner.learned.volumetric_config import (
    VolumetricConfig,
    resolve_volumetric_config,
)

Array = NDArray[np.float64]
NETWORKS = ("vgn", "giga")
#: How to install what these planners need (the error names it when torch is missing).
INSTALL_HINT = (
    "the vgn and giga planners need torch, in the optional 'learned' extra: run "
    "`pip install -e '.[learned]'` (or just `pip install torch`)"
)


def import_torch() -> Any:
    """torch, or :class:`~hsqbench.planner.learned.network.LearnedExtraMissing` saying how."""
    from hsqbench.planner.learned.network import LearnedExtraMissing

    try:
        import torch
    except ImportError as exc:
        raise LearnedExtraMissing(f"{INSTALL_HINT} ({exc})") from exc
    return torch


def available() -> bool:
    """Whether torch imports (for the registry's ``unavailable`` and the tests)."""
    try:
        import_torch()
    except RuntimeError:
        return False
    return True


def cube_origins(points: Array, plane: Array, cfg: VolumetricConfig) -> tuple[Array, Array]:
    """``(origins (T, 3), kept_centres (T, 2))``: the lower corners of cubes whose kept parts
    (inside the detection's x/y bounds) cover the cloud's x/y footprint, and the x/y centres of
    those kept parts. The cube floor lies ``table_height_m`` below the table at each centre."""
    grid = cfg.grid
    bx, by, _ = detection.bound_voxels(cfg.detection, grid.voxel_m)
    bounds = np.array([bx, by], dtype=np.float64)
    # Kept voxels i in [b, n - b - 1]; the grasp of voxel i lies i voxels from the corner.
    kept_m = (grid.voxels - 2 * bounds - 1) * grid.voxel_m
    kept_mid = (bounds + 0.5 * (grid.voxels - 2 * bounds - 1)) * grid.voxel_m
    lo, hi = points[:, :2].min(axis=0), points[:, :2].max(axis=0)
    counts = np.clip(np.ceil((hi - lo) / kept_m), 1, cfg.max_cubes_per_axis).astype(int)
    ticks = []
    for axis in range(2):
        n = counts[axis]
        if n == 1:
            ticks.append(np.array([0.5 * (lo[axis] + hi[axis])]))
        else:
            half = 0.5 * kept_m[axis]
            ticks.append(np.linspace(lo[axis] + half, hi[axis] - half, n))
    cx, cy = np.meshgrid(*ticks, indexing="ij")
    centres = np.column_stack([cx.ravel(), cy.ravel()])
    table_z = -(centres @ plane[:2] + plane[3]) / plane[2]
    origins = np.column_stack([centres - kept_mid, table_z - grid.table_height_m])
    return origins, centres


def quaternion_matrices(quats: Array) -> Array:
    """(M, 3, 3) rotations of unit quaternions (M, 4) given as (x, y, z, w)."""
    q = quats / np.linalg.norm(quats, axis=1, keepdims=True)
    x, y, z, w = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def grasp_frames(quats: Array) -> Array:
    """(M, 3, 3) harness grasp rotations (closing, approach x closing, approach) from the
    networks' quaternions (their y axis closes, their z axis approaches)."""
    rot = quaternion_matrices(quats)
    closing, approach = rot[:, :, 1], rot[:, :, 2]
    return np.stack([closing, np.cross(approach, closing), approach], axis=-1)


def view_yaw(camera: Array, centre: Array) -> Array:
    """(3, 3) rotation about the vertical of a frame in which the camera at ``camera`` lies on
    the -y side of ``centre`` (x, y), as the training camera lay on the cube's (azimuth -90 deg).
    Points map as ``p_frame = p_world @ R``."""
    d = np.asarray(camera, dtype=np.float64)[:2] - np.asarray(centre, dtype=np.float64)[:2]
    if not np.hypot(*d) > 1e-9:
        return np.eye(3)  # straight above: any yaw sees the same
    psi = np.arctan2(d[1], d[0]) + 0.5 * np.pi
    c, s = np.cos(psi), np.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def input_frames(
    views: Sequence[Any], points: Array, kind: str
) -> list[tuple[Array, tuple[Any, ...]]]:
    """``[(yaw rotation, views)]``: the inputs the network runs on. ``fused``: the world axes and
    every view; ``per_view``: each view alone, in the frame that puts its camera on the -y side
    of the cloud's footprint centre (:func:`view_yaw`)."""
    if kind == "fused":
        return [(np.eye(3), tuple(views))]
    centre = 0.5 * (points[:, :2].min(axis=0) + points[:, :2].max(axis=0))
    return [(view_yaw(np.asarray(v.T_world_camera)[:3, 3], centre), (v,)) for v in views]


@dataclass(frozen=True)
class YawedView:
    """A depth image with its camera pose in a yawed frame (what :func:`tsdf.integrate` reads)."""

    depth_m: NDArray
    K: Array
    T_world_camera: Array


def yawed_view(view: Any, yaw: Array) -> Any:
    """``view`` with its camera pose expressed in the frame rotated by ``yaw`` (the view itself
    when ``yaw`` is the identity, so the fused input is bit for bit today's)."""
    if np.array_equal(yaw, np.eye(3)):
        return view
    T = np.array(view.T_world_camera, dtype=np.float64)
    T[:3] = yaw.T @ T[:3]
    return YawedView(depth_m=view.depth_m, K=np.asarray(view.K, dtype=np.float64), T_world_camera=T)


class VolumetricPlanner(PlannerBase):
    """VGN (``network="vgn"``) or GIGA (``"giga"``) behind the planner protocol.

    The weights of every training set the config's ``weights`` names are checked and loaded
    here (a missing or corrupt file fails now, in one line, not at the first plan).
    """

    def __init__(
        self,
        network: str,
        config: VolumetricConfig | str | Path | None = None,
        *,
        name: str | None = None,
    ) -> None:
        if network not in NETWORKS:
            raise ValueError(f"network must be one of {NETWORKS}, got {network!r}")
        torch = import_torch()
        from hsqbench.planner.learned.weights import load_strict, weights_path

        self.network = network
        self.name = name or network
        self.config = resolve_volumetric_config(config)
        self.device = _resolve_device(torch, self.config.device)
        if self.config.torch_threads:
            torch.set_num_threads(self.config.torch_threads)
        self.nets = {}
        for training in sorted(set(self.config.weights.values())):
            path = weights_path(network, training, self.config.weights_url)
            self.nets[training] = load_strict(self._module(), path).to(self.device)

    def _module(self) -> Any:
        if self.network == "vgn":
            from hsqbench.planner.learned.vgn_net import VGNNet

            return VGNNet()
        from hsqbench.planner.learned.giga_net import GIGANet

        return GIGANet()

    def cleaning_config(self) -> CleaningConfig:
        return resolve_config(self.config.planner).cleaning

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """Cubes, TSDF, network and detection (module notes)."""
        cfg = self.config
        views, plane = self._inputs(context)
        timings: dict[str, float] = {}
        tick = time.perf_counter()
        cubes = self._cubes(views, clean.points, plane)
        inputs = np.stack([g.network_input() for *_, grids in cubes for g in grids])
        valid = np.stack([detection.valid_centres(x, cfg.detection) for x in inputs])
        timings["tsdf"] = time.perf_counter() - tick

        tick = time.perf_counter()
        training = cfg.weights_for(context.scene)
        quality, rotation, width = self._predict(training, inputs, valid)
        timings["network"] = time.perf_counter() - tick

        tick = time.perf_counter()
        grasps, first = [], 0
        for yaw, origins, centres, _ in cubes:
            at = slice(first, first + len(origins))
            grasps += self._detect(
                yaw, origins, centres, valid[at], quality[at], rotation[at], width[at]
            )
            first += len(origins)
        # Merge ``best``: every view's grasps ranked by their own quality (ties: view order).
        order = np.argsort([-g.score for g in grasps], kind="stable")
        grasps = [grasps[i] for i in order]
        timings["detection"] = time.perf_counter() - tick
        n_valid = int(valid.sum())
        reason = ""
        if not grasps:
            reason = (
                f"no local maximum of {self.name}'s quality reached "
                f"{cfg.detection.low_quality:g} at the {n_valid} voxels near seen surfaces of "
                f"{len(inputs)} cube(s)"
            )
        surface = np.concatenate(
            [g.surface_points() @ yaw.T for yaw, *_, grids in cubes for g in grids]
        )
        return PlanResult(
            grasps=grasps,
            remaining={"cubes": len(inputs), "valid_voxels": n_valid, "grasps": len(grasps)},
            timings=timings,
            reason=reason,
            surface_points=surface,
        )

    def _inputs(self, context: PlanningContext) -> tuple[Any, Array]:
        """The depth views and the table plane, or a ValueError saying which is missing."""
        if not context.depth_views:
            raise ValueError(
                f"the {self.name} planner reads the depth images (PlanningContext.depth_views); "
                "the harness's trials pass them, a saved cloud alone cannot be planned on"
            )
        plane = validate_plane(context.support_plane)
        if plane is None or abs(plane[2]) < 0.5:
            raise ValueError(
                f"the {self.name} planner needs the table plane (PlanningContext.support_plane) "
                "with its normal near the world's z axis"
            )
        return context.depth_views, plane

    def _cubes(self, views: Any, points: Array, plane: Array) -> list[tuple[Any, ...]]:
        """``[(yaw rotation, origins, centres, TSDF grids)]``, one per network input
        (:func:`input_frames`), the cubes tiled over the cloud in that input's yawed frame."""
        cfg, grid = self.config, self.config.grid
        shape = (grid.voxels,) * 3
        trunc = grid.truncation_voxels * grid.voxel_m
        cubes = []
        for yaw, seen in input_frames(views, points, cfg.input):
            local = points @ yaw  # the cloud in the yawed frame (p' = R^T p)
            local_plane = np.concatenate([plane[:3] @ yaw, plane[3:]])
            origins, centres = cube_origins(local, local_plane, cfg)
            local_views = [yawed_view(v, yaw) for v in seen]
            grids = [
                tsdf.integrate(self._cube_views(local_views, o), o, grid.voxel_m, shape, trunc)
                for o in origins
            ]
            cubes.append((yaw, origins, centres, grids))
        return cubes

    def _cube_views(self, views: list[Any], origin: Array) -> list[Any]:
        """The images a cube's TSDF is integrated from: the cameras' own, or (``viewpoint:
        training``) each re-projected into the training camera of this cube."""
        if self.config.viewpoint == "camera":
            return views
        tv = self.config.training_view
        target = origin + np.asarray(tv.target_m)
        T = viewpoint.camera_on_sphere(target, tv.distance_m, tv.polar_deg, tv.azimuth_deg)
        size = (tv.width_px, tv.height_px)
        return [viewpoint.reproject(v, T, tv.intrinsics(), size, tv.splat_px) for v in views]

    def _predict(self, training: str, inputs: NDArray, valid: NDArray) -> tuple[Any, Any, Any]:
        net = self.nets[training]
        if self.network == "vgn":
            from hsqbench.planner.learned.vgn_net import predict_vgn

            return predict_vgn(net, inputs, self.device)
        from hsqbench.planner.learned.giga_net import predict_giga

        needed = np.stack([detection.smoothing_support(v, self.config.detection) for v in valid])
        return predict_giga(net, inputs, needed, self.device)

    def _detect(
        self,
        yaw: Array,
        origins: Array,
        centres: Array,
        valid: NDArray,
        quality: NDArray,
        rotation: NDArray,
        width: NDArray,
    ) -> list[Grasp]:
        """One input's cubes' detections as world grasps, those another of its cubes owns
        dropped, best first (ties: cube order, then each cube's own order). ``yaw``: the
        rotation of the input's frame in the world (the cubes' positions are in that frame)."""
        vox = self.config.grid.voxel_m
        found = []
        for t in range(len(origins)):  # a handful of cubes, each vectorised
            det = detection.detect(quality[t], width[t], valid[t], self.config.detection, vox)
            at = tuple(det.index.T)
            position = origins[t] + det.index * vox
            gap = np.abs(position[:, None, :2] - centres[None]).max(axis=2)
            own = np.argmin(gap, axis=1) == t
            found.append(
                (position[own], rotation[t][at][own], width[t][at][own] * vox, det.quality[own])
            )
        position, quats, widths, scores = (
            np.concatenate(parts) for parts in zip(*found, strict=True)
        )
        order = np.argsort(-scores, kind="stable")
        frames = grasp_frames(quats[order]) if len(order) else np.zeros((0, 3, 3))
        frames = yaw @ frames  # to the world
        position = position @ yaw.T
        shift = self.config.pads_beyond_tcp_m
        return [
            Grasp(
                position=position[i] + shift * frames[k][:, 2],
                rotation=frames[k],
                width=float(widths[i]),
                score=float(scores[i]),
                factors={"quality": float(scores[i])},
                family=self.network,
            )
            for k, i in enumerate(order)
        ]


def _resolve_device(torch: Any, device: str) -> str:
    if device == "auto":
        return "cuda" if torch.cuda.is_available() else "cpu"
    if device == "cuda" and not torch.cuda.is_available():
        raise RuntimeError("volumetric.device is 'cuda' but torch sees no CUDA device")
    return device
