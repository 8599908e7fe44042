"""Baseline planner settings: ``configs/baselines.yaml`` loaded into typed, frozen dataclasses.

Both baselines share the gripper, the elimination rules and ``q_delta`` with the hsq planner:
``planner`` names the planner config they read those from (stage one's settings too, for
``single-sq``). Only what is specific to a baseline lives here; every default is mirrored, with
its reason, in ``configs/baselines.yaml``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hsqbench.config import load_config, resolve_config_path


@dataclass(frozen=True)
class AntipodalConfig:
    """The antipodal sampler (:mod:`hsqbench.planner.baselines.antipodal`).

    Attributes:
        voxel_m: the cloud is voxel-downsampled to this size before normals and sampling, m.
        normal_neighbours: ``k`` of the PCA normal of each point.
        orientation_radius_m: normals point away from the cloud's centroid within this radius.
        orientation_voxel_m: voxel size of the coarse cloud that centroid is computed on, m.
        n_samples: points sampled (without replacement) as first contacts.
        friction_half_angle_deg: half angle of the friction cone at each contact, degrees.
        ray_radius_m: a cloud point within this distance of the ray is a hit, m.
        min_width_m: hits closer than this along the ray are the sampled point's own surface, m.
        roll_step_deg: approach directions about each closing line, every this many degrees.
    """

    voxel_m: float = 0.003
    normal_neighbours: int = 20
    orientation_radius_m: float = 0.05
    orientation_voxel_m: float = 0.01
    n_samples: int = 400
    friction_half_angle_deg: float = 26.565
    ray_radius_m: float = 0.003
    min_width_m: float = 0.006
    roll_step_deg: float = 30.0

    def __post_init__(self) -> None:
        positive = {
            "voxel_m": self.voxel_m,
            "orientation_radius_m": self.orientation_radius_m,
            "orientation_voxel_m": self.orientation_voxel_m,
            "ray_radius_m": self.ray_radius_m,
            "roll_step_deg": self.roll_step_deg,
        }
        for key, value in positive.items():
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"antipodal.{key} must be > 0, got {value}")
        if self.orientation_voxel_m * np.sqrt(3.0) > self.orientation_radius_m:
            raise ValueError(
                "antipodal.orientation_voxel_m must be at most orientation_radius_m / sqrt(3) "
                f"(each point must reach its own voxel), got {self.orientation_voxel_m} for a "
                f"radius of {self.orientation_radius_m}"
            )
        if self.normal_neighbours < 3:
            raise ValueError(
                f"antipodal.normal_neighbours must be >= 3 (a plane), got {self.normal_neighbours}"
            )
        if self.n_samples < 1:
            raise ValueError(f"antipodal.n_samples must be >= 1, got {self.n_samples}")
        if not 0.0 < self.friction_half_angle_deg < 90.0:
            raise ValueError(
                "antipodal.friction_half_angle_deg must be in (0, 90) degrees, "
                f"got {self.friction_half_angle_deg}"
            )
        if not (np.isfinite(self.min_width_m) and self.min_width_m >= 0.0):
            raise ValueError(f"antipodal.min_width_m must be >= 0, got {self.min_width_m}")
        if abs(360.0 / self.roll_step_deg - round(360.0 / self.roll_step_deg)) > 1e-9:
            raise ValueError(
                f"antipodal.roll_step_deg must divide 360 degrees evenly, got {self.roll_step_deg}"
            )


@dataclass(frozen=True)
class BaselinesConfig:
    """Settings of the ``single-sq`` and ``antipodal`` planners.

    Attributes:
        planner: name or path of the planner config (``configs/planner.yaml``) whose stage-one
            (``single-sq``) and stage-two settings (both: gripper, elimination, ``q_delta``) the
            baselines share with the hsq planner.
        antipodal: the antipodal sampler.
    """

    planner: str = "planner"
    antipodal: AntipodalConfig = field(default_factory=AntipodalConfig)


def load_baselines_config(path: str | Path | None = "baselines") -> BaselinesConfig:
    """Load ``configs/baselines.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(BaselinesConfig, path)


def resolve_baselines_config(config: BaselinesConfig | str | Path | None) -> BaselinesConfig:
    """An instance, a config name or a YAML path; None -> ``configs/baselines.yaml``.

    Files are parsed once per modification time.
    """
    if isinstance(config, BaselinesConfig):
        return config
    if config is not None and not isinstance(config, (str, Path)):
        raise TypeError(
            f"baseline planners take a BaselinesConfig, a config name or a YAML path, got "
            f"{type(config).__name__}; stage settings go in its 'planner' entry"
        )
    path = resolve_config_path("baselines" if config is None else config)
    return _load(str(path), path.stat().st_mtime_ns)


@functools.lru_cache(maxsize=16)
def _load(path: str, mtime_ns: int) -> BaselinesConfig:
    return load_baselines_config(path)
