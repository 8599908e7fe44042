"""The trial runner's configuration (``configs/trial.yaml``): execution geometry and the whole
trial config tree (the packed stop rule: :mod:`hsqbench.sim.stop_rule`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import pairwise
from pathlib import Path
from typing import Any, Literal

from hsqbench.assets.config import AssetsConfig, load_assets_config
from hsqbench.config import expand_names, from_dict, load_tree
from hsqbench.errors import ConfigError
from hsqbench.planner.configs import PlannerConfigs
from hsqbench.planner.oracle import OracleConfig
from hsqbench.sim.clutter.config import ClutterConfig
from hsqbench.sim.ik import IKConfig
from hsqbench.sim.judge import JudgeConfig
from hsqbench.sim.motion import MotionConfig
from hsqbench.sim.perception import PerceptionConfig
from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.robot import RobotConfig
from hsqbench.sim.scene import SceneConfig
from hsqbench.sim.stop_rule import PackedConfig
from hsqbench.sim.surface_sensor import SurfaceSensorConfig
from hsqbench.sim.trial.ordering import OrderingConfig


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
        nudge_extra_m: added to a table nudge so the raised grasp clears the clearance.
        min_lowering_m: a lowering shorter than this is not run (already at release height).
        lowering_fractions: the lowering's depths tried in turn, as fractions of the full one,
            when the full one cannot be solved or would sweep the arm into the bin.
        lowering_shifts_m: at each depth, the lowering is also tried ending this far off the
            bin centre toward where the hand points (horizontally), when it is tilted more than
            ``shift_min_level`` (the horizontal part of its approach axis).
        shift_min_level: below this horizontal part the hand points down and is not shifted.
        withdraw_m: how far the open hand is pulled back along its approach when the object
            is not in the bin after the release (tried shorter like the lowering).
        turn_down_fractions: over the bin, a hand tilted more than ``shift_min_level`` is
            turned about the TCP by the first of these fractions of the turn that would make it
            point straight down that the arm can make (empty: no turn).
        resolve_restarts: IK restarts when a pose is re-solved during execution (the carry
            for the object's real position, the retreat): seeded by the plan, one suffices.
        park_xy_m: where removed objects are parked (x, y; object k at x + k), far outside
            the table, cameras and arm.
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
    nudge_extra_m: float = 0.0005
    min_lowering_m: float = 0.01
    lowering_fractions: tuple[float, ...] = (1.0, 0.75, 0.5, 0.25)
    lowering_shifts_m: tuple[float, ...] = (0.03, 0.06)
    shift_min_level: float = 0.5
    withdraw_m: float = 0.08
    turn_down_fractions: tuple[float, ...] = (1.0, 0.5)
    resolve_restarts: int = 1
    park_xy_m: tuple[float, float] = (10.0, 10.0)

    def __post_init__(self) -> None:
        if self.approach_segments < 1 or self.lift_segments < 1:
            raise ValueError("execution: approach_segments and lift_segments must be >= 1")
        for name in ("pregrasp_distance_m", "lift_height_m", "carry_clearance_m", "withdraw_m"):
            if getattr(self, name) <= 0:
                raise ValueError(f"execution.{name} must be positive, got {getattr(self, name)}")
        sh = self.lowering_shifts_m
        if any(not a < b for a, b in pairwise((0.0, *sh))):
            raise ValueError(
                f"execution.lowering_shifts_m {list(sh)}: positive and increasing, or empty (no "
                "shifted lowering)"
            )
        if not 0.0 <= self.shift_min_level <= 1.0:
            raise ValueError(
                f"execution.shift_min_level must be in [0, 1], got {self.shift_min_level}"
            )
        tf = self.turn_down_fractions
        if any(not 0 < b < a for a, b in pairwise((1.0 + 1e-12, *tf))):
            raise ValueError(
                f"execution.turn_down_fractions {list(tf)}: decreasing values in (0, 1], or "
                "empty (no turn)"
            )
        fr = self.lowering_fractions
        if not fr or fr[0] != 1.0 or any(not 0 < b < a for a, b in pairwise(fr)):
            raise ValueError(
                f"execution.lowering_fractions {list(fr)}: start at 1.0 (the full lowering) and "
                "decrease, every value above 0"
            )


@dataclass(frozen=True)
class TrialConfig:
    """``configs/trial.yaml``: how one trial runs, the whole tree of settings that a trial's
    results depend on (see the comments there for each reason). In YAML each nested config may
    be given by name (``scene: scene`` loads ``configs/scene.yaml``); loaded, it is the object.

    Attributes:
        scene, robot, physics: the scene parts.
        sensor: ``cameras`` (rendered depth, :mod:`hsqbench.sim.perception`) or ``surface``
            (the fast stand-in, :mod:`hsqbench.sim.surface_sensor`).
        perception: the cameras' perception (``sensor: cameras``).
        surface: settings of the stand-in (``sensor: surface``).
        planners: each planner's config (:class:`~hsqbench.planner.configs.PlannerConfigs`).
        graspability: oracle config with which every attempt checks whether the presentation
            is graspable at all (``Attempt.graspable``); None: no check.
        assets: the object library's build settings (hulls, inertia: they change the physics).
        max_ranks: grasps tried in score order before an attempt is ``unreachable``.
        min_cloud_points: fewer perceived points than this: nothing to grasp.
        recorded_scores: how many of the planner's best scores each attempt records
            (``Attempt.top_scores``, the ``top_scores`` column).
        ordering, execution, ik, motion, judge: see their classes.
        packed, pile: the stop rules of packed and pile rounds (:mod:`hsqbench.sim.stop_rule`).
        clutter: VGN/GIGA's clutter-removal protocol (:mod:`hsqbench.sim.clutter`); set, the
            packed and pile rounds run it (free hand, their scenes and camera, its own stop
            rule) instead of the arm's, with this tree's robot hand, physics and planners.
    """

    scene: SceneConfig = field(default_factory=SceneConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    physics: PhysicsConfig = field(default_factory=PhysicsConfig)
    sensor: Literal["cameras", "surface"] = "cameras"
    perception: PerceptionConfig = field(default_factory=PerceptionConfig)
    surface: SurfaceSensorConfig = field(default_factory=SurfaceSensorConfig)
    planners: PlannerConfigs = field(default_factory=PlannerConfigs)
    graspability: OracleConfig | None = field(default_factory=OracleConfig)
    # The library's object lists are data, not settings: the default is configs/assets.yaml.
    assets: AssetsConfig = field(default_factory=load_assets_config)
    max_ranks: int = 48
    min_cloud_points: int = 30
    recorded_scores: int = 5
    ordering: OrderingConfig = field(default_factory=OrderingConfig)
    execution: ExecutionConfig = field(default_factory=ExecutionConfig)
    ik: IKConfig = field(default_factory=IKConfig)
    motion: MotionConfig = field(default_factory=MotionConfig)
    judge: JudgeConfig = field(default_factory=JudgeConfig)
    packed: PackedConfig = field(default_factory=PackedConfig)
    pile: PackedConfig = field(default_factory=PackedConfig)
    clutter: ClutterConfig | None = None

    def __post_init__(self) -> None:
        if self.max_ranks < 1:
            raise ValueError(f"max_ranks must be >= 1, got {self.max_ranks}")
        if self.recorded_scores < 0:
            raise ValueError(f"recorded_scores must be >= 0, got {self.recorded_scores}")


def load_trial_config(
    path: str | Path | None = "trial", overrides: dict[str, Any] | None = None
) -> TrialConfig:
    """The resolved trial config tree of ``configs/trial.yaml`` (or another file), with
    ``overrides`` (``{"perception.tof.sigma_quad_per_m": 0.01, ...}``) applied to its data
    before any dataclass is built (:func:`hsqbench.config.load_tree`); ``None`` gives the
    built-in defaults, which equal ``configs/trial.yaml``."""
    if path is None:
        if overrides:
            raise ValueError("overrides need a config file to apply to")
        return TrialConfig()
    return load_tree(TrialConfig, path, overrides)


def trial_config_from_record(
    data: dict[str, Any], where: str = "run.json", overrides: dict[str, Any] | None = None
) -> TrialConfig:
    """The config tree a run recorded (``backend.trial_config`` of its ``run.json``), for a
    replay, with ``overrides`` applied as :func:`load_trial_config` applies them. Runs made
    before the tree recorded names (``scene: scene``: loaded from today's files) and
    ``planner_config: null`` (each planner's own config: today's ``planners:``)."""
    data = dict(data)
    old = data.pop("planner_config", None)
    if old is not None:
        raise ConfigError(
            f"{where}: planner_config {old!r} was handed to every planner (a run made before "
            "the per-planner map); replay it with a trial config whose planners: names it"
        )
    tree = expand_names(TrialConfig, data)
    if overrides:
        from hsqbench.overrides import apply_overrides

        tree = apply_overrides(tree, overrides, TrialConfig)
    return from_dict(TrialConfig, tree, where)


def named_inputs(config: TrialConfig) -> dict[str, Any]:
    """What the tree names below the level of its configs (files read as they are): the
    planner configs that the baselines and the oracle read, the grippers, and the scene's world
    files. Hashed with the tree, so editing any of them changes a run's config hash."""
    from hsqbench.config import load_config_data, to_dict
    from hsqbench.planner.gripper import resolve_gripper
    from hsqbench.planner.hsq.config import resolve_config
    from hsqbench.sim.scene import world_files

    oracles = [config.planners.oracle, *([config.graspability] if config.graspability else [])]
    named = sorted({config.planners.baselines.planner, *(o.planner_config for o in oracles)})
    grippers = sorted(
        {config.planners.hsq.grasp.gripper, *(resolve_config(n).grasp.gripper for n in named)}
    )
    return {
        "planner_configs": {n: load_config_data(n) for n in named},
        "grippers": {g: to_dict(resolve_gripper(g)) for g in grippers},
        "scene_world": world_files(config.scene),
    }
