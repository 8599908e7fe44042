"""Settings of the volumetric planners ``vgn`` and ``giga``: ``configs/volumetric.yaml``.

Every default is mirrored, with its reason, in ``configs/volumetric.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np

from hsqbench.config import load_cached, load_config

SCENE_KINDS = ("isolated", "packed", "pile")


@dataclass(frozen=True)
class GridConfig:
    """The cube the networks were trained on, and the TSDF fused on it.

    Attributes:
        voxels: voxels along each side.
        size_m: side of the cube, metres.
        truncation_voxels: TSDF truncation, in voxels.
        table_height_m: height of the table plane above the cube's floor.
    """

    voxels: int = 40
    size_m: float = 0.3
    truncation_voxels: float = 4.0
    table_height_m: float = 0.05

    def __post_init__(self) -> None:
        if self.voxels < 8 or self.voxels % 8:
            raise ValueError(f"volumetric.grid.voxels must be a multiple of 8, got {self.voxels}")
        for key in ("size_m", "truncation_voxels", "table_height_m"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"volumetric.grid.{key} must be > 0, got {value}")

    @property
    def voxel_m(self) -> float:
        return self.size_m / self.voxels


@dataclass(frozen=True)
class DetectionConfig:
    """The papers' grasp detection on the network's volumes.

    Attributes:
        smoothing_sigma_voxels: Gaussian smoothing of the quality volume.
        surface_tsdf: network-input value of the surface (voxels above are observed free
            space, between ``empty_tsdf`` and it the inside).
        empty_tsdf: network-input values at most this count as "no surface here".
        free_dilation_voxels: grasp centres must lie within this many voxels of observed
            free space, and not inside an object.
        min_width_voxels, max_width_voxels: predicted widths outside are dropped.
        bound_m: (x, y, z) margins from the cube's lower x, y, z and upper x, y faces in which
            no grasp is kept.
        low_quality: qualities below this are zeroed before everything else.
        quality_threshold: local maxima below this are dropped.
        max_filter_voxels: side of the local-maximum window.
        force_detection: when no voxel reaches ``quality_threshold``, keep the single best
            local maximum above ``low_quality``.
    """

    smoothing_sigma_voxels: float = 1.0
    surface_tsdf: float = 0.5
    empty_tsdf: float = 1e-3
    free_dilation_voxels: int = 2
    min_width_voxels: float = 1.33
    max_width_voxels: float = 9.33
    bound_m: tuple[float, float, float] = (0.02, 0.02, 0.055)
    low_quality: float = 0.5
    quality_threshold: float = 0.9
    max_filter_voxels: int = 4
    force_detection: bool = True

    def __post_init__(self) -> None:
        if not 0.0 < self.min_width_voxels < self.max_width_voxels:
            raise ValueError("volumetric.detection needs 0 < min_width_voxels < max_width_voxels")
        if not 0.0 <= self.low_quality <= self.quality_threshold < 1.0:
            raise ValueError(
                "volumetric.detection needs 0 <= low_quality <= quality_threshold < 1, got "
                f"{self.low_quality}, {self.quality_threshold}"
            )
        if len(self.bound_m) != 3 or min(self.bound_m) < 0:
            raise ValueError(f"volumetric.detection.bound_m must be 3 lengths >= 0: {self.bound_m}")
        if self.max_filter_voxels < 1 or self.free_dilation_voxels < 0:
            raise ValueError("volumetric.detection: max_filter_voxels >= 1, dilation >= 0")
        if self.smoothing_sigma_voxels < 0:
            raise ValueError("volumetric.detection.smoothing_sigma_voxels must be >= 0")


@dataclass(frozen=True)
class TrainingViewConfig:
    """The camera the published weights' TSDFs were rendered from, relative to the cube.

    Attributes:
        target_m: the point it looks at, in the cube's frame (from its lower corner).
        distance_m: its distance from that point.
        polar_deg: its angle from the vertical.
        azimuth_deg: its azimuth about the vertical (-90: on the cube's -y side).
        width_px, height_px, focal_px: its image size and focal length (principal point at the
            image's centre).
        splat_px: each re-projected point fills the pixels this far around its own.
    """

    target_m: tuple[float, float, float] = (0.15, 0.15, 0.1)
    distance_m: float = 0.6
    polar_deg: float = 60.0
    azimuth_deg: float = -90.0
    width_px: int = 640
    height_px: int = 480
    focal_px: float = 540.0
    splat_px: int = 1

    def __post_init__(self) -> None:
        if not (self.distance_m > 0 and 0 < self.polar_deg < 90 and self.focal_px > 0):
            raise ValueError(
                "volumetric.training_view needs distance_m > 0, 0 < polar_deg < 90, focal_px > 0"
            )
        if min(self.width_px, self.height_px) < 1 or self.splat_px < 0:
            raise ValueError("volumetric.training_view: image sizes >= 1 and splat_px >= 0")

    def intrinsics(self) -> np.ndarray:
        return np.array(
            [
                [self.focal_px, 0.0, 0.5 * self.width_px],
                [0.0, self.focal_px, 0.5 * self.height_px],
                [0.0, 0.0, 1.0],
            ]
        )


@dataclass(frozen=True)
class VolumetricConfig:
    """The ``vgn`` and ``giga`` planners (:mod:`hsqbench.planner.learned.volumetric`).

    Attributes:
        planner: planner config whose ``cleaning:`` the input cloud gets (the cloud only places
            the cubes; the networks read the TSDF of the depth images).
        grid: the cube (:class:`GridConfig`).
        detection: the detection (:class:`DetectionConfig`).
        weights: which training set's weights each scene kind uses (``packed`` or ``pile``).
        input: ``per_view``: for each depth image, cubes yawed about the vertical so that its
            camera lies on their -y side, the TSDF integrated from that image alone (as the
            published weights were trained); ``fused``: cubes aligned with the world axes, the
            TSDF fused from every image.
        merge: how the views' grasps become one list with ``per_view``: ``best``, all of them
            ranked by their own quality.
        viewpoint: with ``per_view``, ``camera`` (each cube sees the camera's own image) or
            ``training`` (the image re-projected into ``training_view``'s camera of each cube,
            :mod:`.viewpoint`).
        training_view: that camera (:class:`TrainingViewConfig`).
        max_cubes_per_axis: at most this many cubes along x and along y.
        pads_beyond_tcp_m: the harness's ``P_G`` (midpoint of the pads) lies this far beyond the
            networks' grasp position (their hand's TCP) along the approach.
        weights_url: where missing weight files are fetched from (``{name}.pt`` appended).
        device: ``auto`` (CUDA when torch sees one), ``cpu`` or ``cuda``.
        torch_threads: CPU threads for torch (0: torch's default).
    """

    planner: str = "planner"
    grid: GridConfig = field(default_factory=GridConfig)
    detection: DetectionConfig = field(default_factory=DetectionConfig)
    weights: dict[str, str] = field(
        default_factory=lambda: {"isolated": "packed", "packed": "packed", "pile": "pile"}
    )
    input: Literal["fused", "per_view"] = "per_view"
    merge: Literal["best"] = "best"
    viewpoint: Literal["camera", "training"] = "camera"
    training_view: TrainingViewConfig = field(default_factory=TrainingViewConfig)
    max_cubes_per_axis: int = 3
    pads_beyond_tcp_m: float = 0.041
    weights_url: str = (
        "https://raw.githubusercontent.com/supersglzc/GIGA/"
        "30efe5946cb2622c21f140b3e811f7fcce804c7b/data/models"
    )
    device: Literal["auto", "cpu", "cuda"] = "auto"
    torch_threads: int = 1

    def __post_init__(self) -> None:
        if sorted(self.weights) != sorted(SCENE_KINDS) or not set(self.weights.values()) <= {
            "packed",
            "pile",
        }:
            raise ValueError(
                "volumetric.weights must map each of isolated, packed, pile to packed or pile, "
                f"got {self.weights}"
            )
        if not (np.isfinite(self.pads_beyond_tcp_m) and self.pads_beyond_tcp_m >= 0):
            raise ValueError(
                f"volumetric.pads_beyond_tcp_m must be >= 0 m, got {self.pads_beyond_tcp_m}"
            )
        if self.max_cubes_per_axis < 1 or self.torch_threads < 0:
            raise ValueError("volumetric: max_cubes_per_axis >= 1 and torch_threads >= 0")
        if self.input not in ("fused", "per_view"):
            raise ValueError(f"volumetric.input must be fused or per_view, got {self.input!r}")
        if self.viewpoint not in ("camera", "training"):
            raise ValueError(
                f"volumetric.viewpoint must be camera or training, got {self.viewpoint!r}"
            )
        if self.viewpoint == "training" and self.input != "per_view":
            raise ValueError(
                "volumetric.viewpoint: training re-projects one camera's image per cube; it "
                "needs input: per_view"
            )
        if self.merge != "best":
            raise ValueError(f"volumetric.merge must be best, got {self.merge!r}")
        if self.device not in ("auto", "cpu", "cuda"):
            raise ValueError(f"volumetric.device must be auto, cpu or cuda, got {self.device!r}")

    def weights_for(self, scene: str | None) -> str:
        """``packed`` or ``pile``: the training set of the weights for a scene kind (None:
        a scene of unknown kind, taken as isolated)."""
        return self.weights[scene if scene in SCENE_KINDS else "isolated"]


def resolve_volumetric_config(config: VolumetricConfig | str | Path | None) -> VolumetricConfig:
    """An instance, a config name or a YAML path; None: ``configs/volumetric.yaml``."""
    if isinstance(config, VolumetricConfig):
        return config
    if config is not None and not isinstance(config, (str, Path)):
        raise TypeError(
            "the vgn and giga planners take a VolumetricConfig, a config name or a YAML path, "
            f"got {type(config).__name__}"
        )
    return load_cached(load_volumetric_config, "volumetric" if config is None else config)


def load_volumetric_config(path: str | Path) -> VolumetricConfig:
    """Load ``configs/volumetric.yaml`` or another file (uncached; see the resolver)."""
    return load_config(VolumetricConfig, path)
