"""Perception settings: ``configs/perception.yaml`` loaded into frozen dataclasses.

The sensor model (which errors are simulated), their parameters (:mod:`hsqbench.sim.sensor_noise`),
the workspace crop and table removal (:mod:`hsqbench.sim.table_crop`), the fused cloud's voxel and
what the cameras see; the reasons for each value are in the YAML.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import mujoco

from hsqbench.config import load_config
from hsqbench.sim.sensor_noise import CalibrationErrorConfig, DexNoiseConfig, TofNoiseConfig

SensorModel = Literal["none", "tof", "calibration", "tof+calibration", "dex"]
#: ``dex``: VGN/GIGA's depth noise (:func:`hsqbench.sim.sensor_noise.apply_dex_noise`), for
#: their clutter-removal protocol (:mod:`hsqbench.sim.clutter`).
SENSOR_MODELS: tuple[str, ...] = ("none", "tof", "calibration", "tof+calibration", "dex")


@dataclass(frozen=True)
class CropConfig:
    """Workspace crop and table removal. Lengths in metres."""

    workspace_margin_m: float = 0.02
    table_margin_m: float = 0.005
    refit_table: bool = True
    refit_band_m: float = 0.015
    refit_inlier_m: float = 0.004
    refit_max_tilt_deg: float = 2.0
    refit_min_points: int = 500

    def __post_init__(self) -> None:
        for name in ("workspace_margin_m", "table_margin_m", "refit_band_m", "refit_inlier_m"):
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0 metres, got {getattr(self, name)}")
        if self.refit_min_points < 3:
            raise ValueError(f"refit_min_points must be >= 3, got {self.refit_min_points}")


@dataclass(frozen=True)
class PerceptionConfig:
    """``configs/perception.yaml``; see the comments there for every value's reason."""

    sensor_model: SensorModel = "tof+calibration"
    tof: TofNoiseConfig = field(default_factory=TofNoiseConfig)
    calibration: CalibrationErrorConfig = field(default_factory=CalibrationErrorConfig)
    dex: DexNoiseConfig = field(default_factory=DexNoiseConfig)
    crop: CropConfig = field(default_factory=CropConfig)
    voxel_m: float = 0.002
    geom_groups: tuple[int, ...] = (0, 1, 2)
    drop_robot_pixels: bool = False

    def __post_init__(self) -> None:
        if self.sensor_model not in SENSOR_MODELS:
            raise ValueError(f"sensor_model {self.sensor_model!r} is not one of {SENSOR_MODELS}")
        if not self.voxel_m > 0:
            raise ValueError(f"voxel_m must be positive metres, got {self.voxel_m}")
        bad = [g for g in self.geom_groups if not 0 <= g < mujoco.mjNGROUP]
        if bad:
            raise ValueError(f"geom_groups {bad} outside 0..{mujoco.mjNGROUP - 1}")

    @property
    def tof_on(self) -> bool:
        return "tof" in self.sensor_model

    @property
    def dex_on(self) -> bool:
        return self.sensor_model == "dex"

    @property
    def calibration_on(self) -> bool:
        return "calibration" in self.sensor_model


def load_perception_config(path: str | Path | None = "perception") -> PerceptionConfig:
    """Load ``configs/perception.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(PerceptionConfig, path)
