"""The ``vgn`` and ``giga`` planners: VGN and GIGA with their published weights, in the harness.

Per observation (:meth:`VolumetricPlanner.stages`):

1. **Cubes.** The networks see one 0.30 m cube (40^3 voxels of 7.5 mm) with the table 5 cm above
   its floor; the workspace is wider. Cubes, axis-aligned with the world, are tiled over the
   footprint of the (cleaned) cloud so that the part of each cube where grasps are kept (inside
   the detection's x/y bounds) covers it: one cube for an isolated object, up to
   ``max_cubes_per_axis`` per axis for a packed scene (:func:`cube_origins`).
2. **TSDF.** Each cube's TSDF is fused from the harness's depth images, the same noisy images the
   cloud of every other planner comes from (``PlanningContext.depth_views``; :mod:`.tsdf`).
3. **Network.** All cubes in one batch: VGN's volumes, or GIGA's encoder and its decoders at the
   voxels the detection reads (:mod:`.vgn_net`, :mod:`.giga_net`).
4. **Detection** as the papers do it (:mod:`.detection`); a grasp in the overlap of two cubes is
   kept only from the cube whose kept part is centred nearest to it, so no grasp comes twice.

Grasps: the network's position (voxel index times voxel size, the networks' convention) is its
hand's TCP; ``P_G`` lies ``pads_beyond_tcp_m`` further along the approach (the config says why);
the orientation's y axis is the closing and z the approach axis; width as predicted.
Scores are the smoothed quality. The weights follow the scene kind
(``PlanningContext.scene``): packed weights in isolated and packed scenes, pile weights in piles.
Nothing is random: the same observation gives the same grasps whatever the seed.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.api import PlanningContext, PlanResult, validate_plane
from hsqbench.planner.base import CleanInput, PlannerBase
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.hsq.config import resolve_config
from hsqbench.planner.learned import detection, tsdf
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
        cfg, grid = self.config, self.config.grid
        views = context.depth_views
        if not views:
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
        timings: dict[str, float] = {}
        tick = time.perf_counter()
        origins, centres = cube_origins(clean.points, plane, cfg)
        shape = (grid.voxels,) * 3
        trunc = grid.truncation_voxels * grid.voxel_m
        grids = [tsdf.integrate(views, o, grid.voxel_m, shape, trunc) for o in origins]
        inputs = np.stack([g.network_input() for g in grids])
        valid = np.stack([detection.valid_centres(x, cfg.detection) for x in inputs])
        timings["tsdf"] = time.perf_counter() - tick

        tick = time.perf_counter()
        training = cfg.weights_for(context.scene)
        quality, rotation, width = self._predict(training, inputs, valid)
        timings["network"] = time.perf_counter() - tick

        tick = time.perf_counter()
        grasps = self._detect(origins, centres, valid, quality, rotation, width)
        timings["detection"] = time.perf_counter() - tick
        n_valid = int(valid.sum())
        reason = ""
        if not grasps:
            reason = (
                f"no local maximum of {self.name}'s quality reached "
                f"{cfg.detection.low_quality:g} at the {n_valid} voxels near seen surfaces of "
                f"{len(origins)} cube(s)"
            )
        surface = np.concatenate([g.surface_points() for g in grids])
        return PlanResult(
            grasps=grasps,
            remaining={"cubes": len(origins), "valid_voxels": n_valid, "grasps": len(grasps)},
            timings=timings,
            reason=reason,
            surface_points=surface,
        )

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
        origins: Array,
        centres: Array,
        valid: NDArray,
        quality: NDArray,
        rotation: NDArray,
        width: NDArray,
    ) -> list[Grasp]:
        """Each cube's detections as harness grasps, those another cube owns dropped, best
        first (ties: cube order, then each cube's own order)."""
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
