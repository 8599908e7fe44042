"""Settings of VGN/GIGA's clutter-removal protocol (``configs/clutter.yaml``): the free hand's
grasp execution, their scenes, their camera and the round rule. Every value's source (repository,
file, value) is in the YAML."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from hsqbench.errors import ConfigError
from hsqbench.sim.perception_config import CropConfig, PerceptionConfig
from hsqbench.sim.stop_rule import PackedConfig


@dataclass(frozen=True)
class HandExecutionConfig:
    """How the free hand executes a grasp (their ``ClutterRemovalSim.execute_grasp``).

    Attributes:
        pregrasp_offset_m: the hand starts this far back along the approach axis.
        retreat_m: the lift after closing.
        side_grasp_angle_deg: an approach more than this from straight down lifts straight up
            (world z); otherwise the lift goes back along the approach.
        step_m, speed_mps: the TCP moves in straight steps of ``step_m`` at ``speed_mps``.
        allow_contact: a contact during the approach stops the approach there and the hand
            closes anyway (True: the clutter-removal runs); False fails the grasp.
        close_time_s: longest time given to the fingers to close.
        gripper_still_mps: fingers slower than this have stopped (closing ends early).
        min_width_fraction: success needs the fingers wider than this fraction of the opening.
        park_m: where the hand waits between grasps (out of the cameras' view).
    """

    pregrasp_offset_m: float = 0.05
    retreat_m: float = 0.1
    side_grasp_angle_deg: float = 60.0
    step_m: float = 0.002
    speed_mps: float = 0.1
    allow_contact: bool = True
    close_time_s: float = 1.5
    gripper_still_mps: float = 0.002
    min_width_fraction: float = 0.1
    park_m: tuple[float, float, float] = (5.0, 5.0, 1.0)

    def __post_init__(self) -> None:
        for name in ("pregrasp_offset_m", "retreat_m", "step_m", "speed_mps", "close_time_s"):
            if not getattr(self, name) > 0:
                raise ConfigError(
                    f"clutter.hand.{name} must be positive, got {getattr(self, name)}"
                )
        if not 0.0 <= self.min_width_fraction < 1.0:
            raise ConfigError(
                f"clutter.hand.min_width_fraction must be in [0, 1), got {self.min_width_fraction}"
            )


@dataclass(frozen=True)
class ClutterSceneConfig:
    """Their world and scene generation (``reset``, ``generate_packed_scene``,
    ``generate_pile_scene``, ``remove_and_wait``). Lengths in metres, in their world frame: the
    workspace cube spans [0, size_m] on x, y and z, the table top lies at ``table_height_m``.

    Attributes:
        size_m: the workspace cube's edge.
        table_height_m: the table top's height in the cube.
        table_half_m: half edge of the square table top (centred on the cube).
        packed_xy_m: range of the x and y of a packed object's centre.
        packed_scale: range of a packed object's size scale.
        packed_max_attempts: placements tried in a packed scene before it stops short.
        packed_gap_m: a placed object's lowest point above the table.
        pile_box_lo_m, pile_box_hi_m: x/y corners of the pile's temporary box (inside).
        pile_wall_height_m, pile_wall_thickness_m: its walls.
        pile_xy_fraction: range of a dropped object's x and y, as fractions of ``size_m``.
        pile_drop_height_m: drop height above the table.
        pile_scale: range of a pile object's size scale.
        pile_rest_timeout_s: time each dropped object gets to come to rest.
        rest_timeout_s, rest_check_s, rest_speed_mps: ``wait_for_objects_to_rest`` (after a
            scene's generation and after each grasp): the scene runs in ``rest_check_s`` chunks
            until every object moves slower than ``rest_speed_mps`` or ``rest_timeout_s``.
    """

    size_m: float = 0.3
    table_height_m: float = 0.05
    table_half_m: float = 0.5
    packed_xy_m: tuple[float, float] = (0.08, 0.22)
    packed_scale: tuple[float, float] = (0.7, 0.9)
    packed_max_attempts: int = 12
    packed_gap_m: float = 0.002
    pile_box_lo_m: tuple[float, float] = (0.02, 0.02)
    pile_box_hi_m: tuple[float, float] = (0.28, 0.28)
    pile_wall_height_m: float = 0.2
    pile_wall_thickness_m: float = 0.02
    pile_xy_fraction: tuple[float, float] = (1.0 / 3.0, 2.0 / 3.0)
    pile_drop_height_m: float = 0.2
    pile_scale: tuple[float, float] = (0.8, 1.0)
    pile_rest_timeout_s: float = 1.0
    rest_timeout_s: float = 2.0
    rest_check_s: float = 0.25
    rest_speed_mps: float = 0.01

    def __post_init__(self) -> None:
        for name in ("packed_xy_m", "packed_scale", "pile_xy_fraction", "pile_scale"):
            lo, hi = getattr(self, name)
            if not lo <= hi:
                raise ConfigError(f"clutter.scene.{name} must be (low, high), got {(lo, hi)}")
        if self.packed_max_attempts < 1:
            raise ConfigError("clutter.scene.packed_max_attempts must be >= 1")
        if not (np.array(self.pile_box_lo_m) < np.array(self.pile_box_hi_m)).all():
            raise ConfigError("clutter.scene.pile_box_lo_m must lie below pile_box_hi_m")


@dataclass(frozen=True)
class ClutterCameraConfig:
    """Their depth camera(s) (``acquire_tsdf``, ``camera_on_sphere``, ``CameraIntrinsic``).

    Attributes:
        views: ``side`` (GIGA's one side view) or ``ring`` (VGN's ``n_views`` views on a circle).
        n_views: views of the ring.
        width_px, height_px, focal_px: the intrinsics (square pixels, centred principal point).
        min_range_m, max_range_m: near and far planes.
        radius_factor: camera distance from the look-at point, in workspace sizes.
        side_origin_height_fraction, side_polar_deg, side_azimuth_deg: the side view's look-at
            height (fraction of the size), angle from vertical and azimuth.
        ring_origin_height_fraction, ring_polar_deg: the ring's look-at height and angle.
    """

    views: Literal["side", "ring"] = "side"
    n_views: int = 6
    width_px: int = 640
    height_px: int = 480
    focal_px: float = 540.0
    min_range_m: float = 0.1
    max_range_m: float = 2.0
    radius_factor: float = 2.0
    side_origin_height_fraction: float = 1.0 / 3.0
    side_polar_deg: float = 60.0
    side_azimuth_deg: float = -90.0
    ring_origin_height_fraction: float = 0.0
    ring_polar_deg: float = 30.0

    def __post_init__(self) -> None:
        if self.views not in ("side", "ring"):
            raise ConfigError(f"clutter.camera.views must be side or ring, got {self.views!r}")
        if self.n_views < 1:
            raise ConfigError("clutter.camera.n_views must be >= 1")

    @property
    def fovy_deg(self) -> float:
        return float(np.degrees(2.0 * np.arctan(0.5 * self.height_px / self.focal_px)))


@dataclass(frozen=True)
class ClutterConfig:
    """VGN/GIGA's clutter removal (``configs/clutter.yaml``), set as ``clutter:`` of a trial
    config: its packed and pile rounds then run this protocol (:mod:`hsqbench.sim.clutter`).

    Attributes:
        executor: ``hand`` (theirs: the free hand) or ``arm`` (the bridge's first step: the
            same scenes in front of the harness's Panda, executed by its arm up to the lift,
            :mod:`hsqbench.sim.clutter.arm`).
        arm_cube_xy_m: with ``arm``, where their workspace cube's corner lies in the arm's
            world (x, y; its floor is the table top less ``scene.table_height_m``).
        arm_sensing: with ``arm``, ``theirs`` (their camera and noise, ``camera`` and
            ``perception`` here) or ``harness`` (the bridge's second step: the trial config's
            own depth cameras and perception, their crop kept).
        arm_until: with ``arm``, the last phase of the harness's execution: ``lift`` (their
            success test: held after the lift) or ``release`` (the bridge's third step: carried
            to the bin and released there, the harness's success).
    """

    executor: Literal["hand", "arm"] = "hand"
    arm_cube_xy_m: tuple[float, float] = (0.35, -0.15)
    arm_sensing: Literal["theirs", "harness"] = "theirs"
    arm_until: Literal["lift", "release"] = "lift"

    hand: HandExecutionConfig = field(default_factory=HandExecutionConfig)
    scene: ClutterSceneConfig = field(default_factory=ClutterSceneConfig)
    camera: ClutterCameraConfig = field(default_factory=ClutterCameraConfig)
    perception: PerceptionConfig = field(
        default_factory=lambda: PerceptionConfig(
            sensor_model="dex",
            crop=CropConfig(workspace_margin_m=0.0, table_margin_m=0.005, refit_table=False),
        )
    )
    rule: PackedConfig = field(
        default_factory=lambda: PackedConfig(
            max_consecutive_failures=2, max_attempts=15, stop_on_no_grasp=True
        )
    )

    def __post_init__(self) -> None:
        if self.executor not in ("hand", "arm"):
            raise ConfigError(f"clutter.executor must be hand or arm, got {self.executor!r}")
        if self.arm_sensing not in ("theirs", "harness"):
            raise ConfigError(f"clutter.arm_sensing: theirs or harness, got {self.arm_sensing!r}")
        if self.arm_until not in ("lift", "release"):
            raise ConfigError(f"clutter.arm_until: lift or release, got {self.arm_until!r}")
