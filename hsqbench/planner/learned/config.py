"""Contact-GraspNet planner settings: ``configs/contact_graspnet.yaml`` in a frozen dataclass.

Every default is mirrored, with its reason, in ``configs/contact_graspnet.yaml``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from hsqbench.config import load_cached, load_config


@dataclass(frozen=True)
class ContactGraspNetConfig:
    """The ``contact-graspnet`` planner (:mod:`hsqbench.planner.learned.contact_graspnet`).

    Attributes:
        planner: name or path of the planner config whose ``cleaning:`` (flying pixels removed
            before planning) and, with ``eliminate``, ``grasp:`` settings (gripper, rules) the
            network shares with hsq and the baselines.
        input_frame: the frame the cloud is given to the network in: ``world_centred`` (world
            axes, z up, origin at the cloud's mean: how the cgn-pytorch weights were trained)
            or ``camera`` (a camera's optical frame, z forward: the original TensorFlow
            release's convention).
        views: ``fused`` (the fused cloud in one pass), ``per_camera`` (each camera's
            visible part by hidden point removal on its own, grasps merged) or ``per_image``
            (each camera's part read off its own depth image, as the network was trained on
            one rendered view; grasps merged).
        image_tolerance_m: with ``per_image``, a cloud point belongs to a camera when it lies
            within this distance of the depth that camera's image measured along its pixel.
        table_patch_radius_m: the network was trained on scenes with the table in view; the
            harness removes it, so a synthetic table patch of this radius around the object,
            on the support plane, is added to the network's input (its grasps on the patch are
            dropped); 0 adds none.
        table_spacing_m: grid spacing of that patch, metres.
        input_voxel_m: the cloud (and patch) is voxel-downsampled to this before the network,
            metres (0: as given).
        max_input_points: at most this many points go in (random subset, seeded).
        confidence_threshold: grasps with a lower confidence are dropped.
        max_grasps: at most this many grasps, best confidence first (0: all).
        gripper_depth_m: base-to-fingertip-centre distance the network's poses use, metres.
        width_source: ``cloud`` (the other contact found on the cloud along the closing line) or
            ``network`` (the pose as the package places it); see :mod:`.width`.
        width_ray_radius_m: cloud points within this distance of the closing line count, m.
        width_min_m: points nearer than this to the contact along the line are its own surface.
        width_reach_m: points farther than this along the line are not looked at, m.
        eliminate: run the harness's elimination rules (those of hsq and the baselines) on the
            network's grasps.
        device: ``auto`` (CUDA when present, else CPU), ``cpu`` or ``cuda``.
        torch_threads: CPU threads for torch (0: leave torch's default).
    """

    planner: str = "planner"
    input_frame: Literal["world_centred", "camera"] = "world_centred"
    views: Literal["fused", "per_camera", "per_image"] = "fused"
    image_tolerance_m: float = 0.01
    table_patch_radius_m: float = 0.3
    table_spacing_m: float = 0.005
    input_voxel_m: float = 0.003
    max_input_points: int = 20000
    confidence_threshold: float = 0.5
    max_grasps: int = 0
    gripper_depth_m: float = 0.1034
    width_source: Literal["cloud", "network"] = "cloud"
    width_ray_radius_m: float = 0.003
    width_min_m: float = 0.006
    width_reach_m: float = 0.1
    eliminate: bool = False
    device: Literal["auto", "cpu", "cuda"] = "auto"
    torch_threads: int = 1

    def __post_init__(self) -> None:
        for key in ("table_patch_radius_m", "input_voxel_m"):
            value = getattr(self, key)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"contact_graspnet.{key} must be >= 0 m, got {value}")
        for key in (
            "table_spacing_m",
            "gripper_depth_m",
            "image_tolerance_m",
            "width_ray_radius_m",
            "width_reach_m",
        ):
            value = getattr(self, key)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"contact_graspnet.{key} must be > 0 m, got {value}")
        if not 0.0 <= self.width_min_m < self.width_reach_m:
            raise ValueError(
                "contact_graspnet.width_min_m must be in [0, width_reach_m), got "
                f"{self.width_min_m}"
            )
        if not 0.0 <= self.confidence_threshold < 1.0:
            raise ValueError(
                "contact_graspnet.confidence_threshold must be in [0, 1), got "
                f"{self.confidence_threshold}"
            )
        if self.max_input_points < 2048:
            raise ValueError(
                "contact_graspnet.max_input_points must be >= 2048 (the network's first "
                f"layer samples 2048 centres), got {self.max_input_points}"
            )
        if self.max_grasps < 0 or self.torch_threads < 0:
            raise ValueError("contact_graspnet.max_grasps and torch_threads must be >= 0")


def load_contact_graspnet_config(
    path: str | Path | None = "contact_graspnet",
) -> ContactGraspNetConfig:
    """Load ``configs/contact_graspnet.yaml`` (or another file); None: the built-in defaults."""
    return load_config(ContactGraspNetConfig, path)


def resolve_contact_graspnet_config(
    config: ContactGraspNetConfig | str | Path | None,
) -> ContactGraspNetConfig:
    """An instance, a config name or a YAML path; None: ``configs/contact_graspnet.yaml``."""
    if isinstance(config, ContactGraspNetConfig):
        return config
    if config is not None and not isinstance(config, (str, Path)):
        raise TypeError(
            "the contact-graspnet planner takes a ContactGraspNetConfig, a config name or a "
            f"YAML path, got {type(config).__name__}"
        )
    return load_cached(
        load_contact_graspnet_config, "contact_graspnet" if config is None else config
    )
