"""The trial runner's configuration (``configs/trial.yaml``): execution geometry, the packed
stop rule and the whole trial config."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from hsqbench.config import load_config
from hsqbench.sim.ik import IKConfig
from hsqbench.sim.judge import JudgeConfig
from hsqbench.sim.motion import MotionConfig
from hsqbench.sim.surface_sensor import SurfaceSensorConfig


@dataclass(frozen=True)
class ExecutionConfig:
    """Geometry of the grasp execution, metres (reasons in ``configs/trial.yaml``).

    Attributes:
        pregrasp_distance_m: pre-grasp pose distance back along the approach axis.
        approach_segments: IK waypoints on the approach line (segments).
        lift_height_m: smallest lift of the TCP.
        lift_segments: IK waypoints on the lift line (segments).
        hover_clearance_m: gap between the hand's lowest point and the cloud's top at the hover
            pose (straight above a pre-grasp that is lower than that).
        waypoint_spacing_m: IK waypoint spacing on the descent from the hover pose.
        table_nudge_max_m: a grasp whose fingers would come closer to the table than the IK
            clearance by at most this much is raised by the deficit.
        hover_raise_m: how much higher the hover pose goes when the joint-space move to the
            lower one would swing the arm through the objects.
        cloud_voxel_m: the cloud is thinned to this voxel size for the arm's collision checks.
        cloud_clearance_m: the arm's bounding boxes, grown by this, must hold fewer than
            ``cloud_min_points`` cloud points on the way to the pre-grasp.
        cloud_min_points: that many points in a box are an obstacle (fewer: sensor outliers).
        carry_clearance_m: height of the object's bottom above the bin walls while carried.
        release_height_m: height of the object's bottom above the bin floor at release.
        retreat_height_m: TCP rise before returning home after an attempt (packed rounds).
        release_gap_m: the hand has let go when it is this much wider than when it held.
    """

    pregrasp_distance_m: float = 0.1
    approach_segments: int = 4
    lift_height_m: float = 0.1
    lift_segments: int = 4
    hover_clearance_m: float = 0.03
    waypoint_spacing_m: float = 0.05
    table_nudge_max_m: float = 0.005
    hover_raise_m: float = 0.15
    cloud_voxel_m: float = 0.01
    cloud_clearance_m: float = 0.01
    cloud_min_points: int = 3
    carry_clearance_m: float = 0.04
    release_height_m: float = 0.03
    retreat_height_m: float = 0.1
    release_gap_m: float = 0.01

    def __post_init__(self) -> None:
        if self.approach_segments < 1 or self.lift_segments < 1:
            raise ValueError("execution: approach_segments and lift_segments must be >= 1")
        for name in ("pregrasp_distance_m", "lift_height_m", "carry_clearance_m"):
            if getattr(self, name) <= 0:
                raise ValueError(f"execution.{name} must be positive, got {getattr(self, name)}")


@dataclass(frozen=True)
class PackedConfig:
    """Packed-round rule: stop after ``max_consecutive_failures`` failures in a row (the
    paper: two) or ``max_attempts`` attempts (a cap that the rule reaches first in practice)."""

    max_consecutive_failures: int = 2
    max_attempts: int = 15

    def __post_init__(self) -> None:
        if self.max_consecutive_failures < 1 or self.max_attempts < 1:
            raise ValueError("packed: max_consecutive_failures and max_attempts must be >= 1")


@dataclass(frozen=True)
class TrialConfig:
    """``configs/trial.yaml``: how one trial runs (see the comments there for each reason).

    Attributes:
        scene, robot, physics: config names (in ``configs/``) of the scene parts.
        sensor: ``cameras`` (rendered depth, :mod:`hsqbench.sim.perception`) or ``surface``
            (the fast stand-in, :mod:`hsqbench.sim.surface_sensor`).
        perception: config name of the cameras' perception (``sensor: cameras``).
        surface: settings of the stand-in (``sensor: surface``).
        planner_config: config handed to ``get_planner`` (None: the planner's default).
        graspability: oracle config (``configs/oracle.yaml``) with which every attempt checks
            whether the presentation is graspable at all (``Attempt.graspable``); None: no check.
        max_ranks: grasps tried in score order before an attempt is ``unreachable``.
        min_cloud_points: fewer perceived points than this: nothing to grasp.
        execution, ik, motion, judge, packed: see their classes.
    """

    scene: str = "scene"
    robot: str = "robot"
    physics: str = "physics"
    sensor: Literal["cameras", "surface"] = "cameras"
    perception: str = "perception"
    surface: SurfaceSensorConfig = field(default_factory=SurfaceSensorConfig)
    planner_config: str | None = None
    graspability: str | None = "oracle"
    max_ranks: int = 48
    min_cloud_points: int = 30
    execution: ExecutionConfig = field(default_factory=ExecutionConfig)
    ik: IKConfig = field(default_factory=IKConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    judge: JudgeConfig = field(default_factory=JudgeConfig)
    packed: PackedConfig = field(default_factory=PackedConfig)

    def __post_init__(self) -> None:
        if self.max_ranks < 1:
            raise ValueError(f"max_ranks must be >= 1, got {self.max_ranks}")


def load_trial_config(path: str | Path | None = "trial") -> TrialConfig:
    """Load ``configs/trial.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(TrialConfig, path)
