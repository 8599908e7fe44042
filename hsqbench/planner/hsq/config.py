"""Planner configuration: ``configs/planner.yaml`` loaded into typed, frozen dataclasses.

Three sections: ``cleaning`` (before both stages, :mod:`hsqbench.planner.cleaning`), ``recovery``
(stage one) and ``grasp`` (stage two), and ``additions``: one switch per addition of ours to the
paper (:mod:`hsqbench.planner.hsq.additions`); a switch that is off sets the paper's values in its
section. Every default here is mirrored, with its reason, in ``configs/planner.yaml``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from hsqbench.config import load_cached, load_config
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.hsq.additions import ADDITIONS, AdditionsConfig


@dataclass(frozen=True)
class RecoveryConfig:
    """Stage one: hidden superquadric recovery (owned by ``hsqbench.planner.hsq.stage_one.recovery``).

    Lengths in metres; weights and probabilities dimensionless. Reasons for each default are in
    the ``recovery:`` section of ``configs/planner.yaml``.
    """

    # Packed scenes: one stage one per object (hsqbench.planner.hsq.stage_one.clusters).
    split_objects: bool = True
    cluster_distance_m: float = 0.01
    cluster_voxel_m: float = 0.005
    min_cluster_points: int = 50
    # Downsampling.
    voxel_size_m: float = 0.004
    max_fit_points: int = 1500
    # Seeds: the paper's K rule, counted on a cloud of the paper's sensor density.
    k_count_voxel_m: float = 0.002
    kmeans_parts_factor: float = 1.5
    max_parts: int = 32
    kmeans_n_init: int = 1
    duplicate_iou: float = 0.8
    no_grasp_redraws: int = 2
    # Probabilistic model.
    outlier_weight: float = 0.2
    hidden_outlier_weight: float = 0.9
    workspace_margin_m: float = 0.005
    # EMS inference.
    em_max_iterations: int = 30
    lm_steps: int = 2
    em_tolerance: float = 1e-3
    max_switches: int = 2
    hidden_max_switches: int = 1
    switch_tolerance: float = 0.05
    switch_candidates: int = 3
    switch_iterations: int = 3
    switch_gain: float = 0.1
    start_eps: tuple[tuple[float, float], ...] = ((1.0, 1.0), (0.3, 0.3), (1.7, 1.7))
    dual_scale_ratio: float = 0.7
    eps_min: float = 0.1
    eps_max: float = 2.0
    scale_min_m: float = 0.002
    sigma_min_m: float = 0.0005
    hidden_sigma_decay: float = 0.7
    # Outputs.
    inlier_threshold: float = 0.5
    surface_spacing_m: float = 0.003
    max_surface_samples: int = 12000
    coverage_distance_m: float = 0.004

    def __post_init__(self) -> None:
        positive = (
            "cluster_distance_m",
            "cluster_voxel_m",
            "voxel_size_m",
            "k_count_voxel_m",
            "kmeans_parts_factor",
            "scale_min_m",
            "sigma_min_m",
            "surface_spacing_m",
            "coverage_distance_m",
        )
        for name in positive:
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be positive, got {getattr(self, name)}")
        for name in ("outlier_weight", "hidden_outlier_weight", "inlier_threshold"):
            if not 0.0 < getattr(self, name) < 1.0:
                raise ValueError(f"{name} must lie in (0, 1), got {getattr(self, name)}")
        if not 0.0 < self.eps_min < self.eps_max <= 2.0:
            raise ValueError(f"need 0 < eps_min < eps_max <= 2, got {self.eps_min}, {self.eps_max}")
        if self.max_surface_samples < 100:
            raise ValueError(f"max_surface_samples must be >= 100, got {self.max_surface_samples}")
        if isinstance(self.no_grasp_redraws, bool) or not (
            isinstance(self.no_grasp_redraws, int) and self.no_grasp_redraws >= 0
        ):
            raise ValueError(
                f"no_grasp_redraws must be a whole number >= 0 (0: no redraw), got "
                f"{self.no_grasp_redraws!r}"
            )
        if self.max_fit_points < 11 or self.max_parts < 1 or self.em_max_iterations < 1:
            raise ValueError("max_fit_points >= 11, max_parts >= 1, em_max_iterations >= 1")
        if not 0.0 <= self.hidden_sigma_decay < 1.0:
            raise ValueError(
                f"hidden_sigma_decay must lie in [0, 1), got {self.hidden_sigma_decay}"
            )
        if not self.start_eps:
            raise ValueError("start_eps needs at least one (eps1, eps2) pair")
        if self.cluster_voxel_m >= self.cluster_distance_m:
            raise ValueError(
                "cluster_voxel_m must be below cluster_distance_m (neighbouring voxels of one "
                f"surface must link), got {self.cluster_voxel_m} >= {self.cluster_distance_m}"
            )
        if self.min_cluster_points < 11:
            raise ValueError(
                "min_cluster_points must be >= 11 (a superquadric has 11 parameters), "
                f"got {self.min_cluster_points}"
            )


@dataclass(frozen=True)
class GraspConfig:
    """Stage two: grasp synthesis, elimination and scoring (``hsqbench.planner.hsq.stage_two.synthesis``,
    ``elimination``, ``scoring``).

    Lengths in metres, angles in degrees, the q's as in the paper. Reasons for each default are in
    the ``grasp:`` section of ``configs/planner.yaml``.
    """

    # The gripper: a name in configs/ or a YAML path, loaded into GripperModel.
    gripper: str = "gripper"
    # Synthesis.
    roll_step_deg: float = 10.0
    slide_step_m: float = 0.015
    rotate_step_deg: float = 22.5
    flat_eps_max: float = 0.5
    round_eps2_tol: float = 0.25
    round_axis_ratio_tol: float = 0.1
    max_tilt_deg: float = 26.6
    slide_all_shapes: bool = True
    min_part_scale_m: float = 0.0025
    level_table_lines: bool = True
    level_max_angle_deg: float = 45.0
    pinch_max_lift_m: float = 0.008
    # Elimination (sweep_rule: set by additions.sweep).
    sweep_rule: bool = True
    duplicate_distance_m: float = 0.003
    duplicate_angle_deg: float = 3.0
    elimination_voxel_m: float = 0.003
    opening_margin_m: float = 0.004
    support_radius_m: float = 0.01
    contact_depth_m: float = 0.01
    support_min_points: int = 5
    support_min_fraction: float = 0.1
    support_max_tilt_deg: float = 30.0
    unseen_incidence_deg: float = 75.0
    unseen_max_down_deg: float = 30.0
    approach_distance_m: float = 0.05
    table_clearance_m: float = 0.003
    max_obstacle_points: int = 0
    # Rule 6, the hidden bodies (body_rule: set by additions.hidden_bodies).
    body_rule: bool = True
    body_margin_m: float = 0.003
    body_spacing_m: float = 0.005
    body_pixel_m: float = 0.004
    body_carve_margin_m: float = 0.004
    # Scoring.
    q_alpha: float = 0.002
    q_gamma: float = 0.5
    q_delta: float = 0.005
    alpha_unit_m: float = 0.1
    contact_radius_m: float = 0.0085

    def __post_init__(self) -> None:
        positive = {
            "roll_step_deg": self.roll_step_deg,
            "slide_step_m": self.slide_step_m,
            "rotate_step_deg": self.rotate_step_deg,
            "elimination_voxel_m": self.elimination_voxel_m,
            "duplicate_distance_m": self.duplicate_distance_m,
            "duplicate_angle_deg": self.duplicate_angle_deg,
            "support_radius_m": self.support_radius_m,
            "contact_depth_m": self.contact_depth_m,
            "q_alpha": self.q_alpha,
            "q_gamma": self.q_gamma,
            "q_delta": self.q_delta,
            "contact_radius_m": self.contact_radius_m,
            "alpha_unit_m": self.alpha_unit_m,
            "body_spacing_m": self.body_spacing_m,
            "body_pixel_m": self.body_pixel_m,
        }
        for key, value in positive.items():
            if not value > 0:
                raise ValueError(f"grasp.{key} must be > 0, got {value}")
        for key in ("roll_step_deg", "rotate_step_deg"):
            step = getattr(self, key)
            if abs(360.0 / step - round(360.0 / step)) > 1e-9:
                raise ValueError(f"grasp.{key} must divide 360 degrees evenly, got {step}")
        non_negative = {
            "flat_eps_max": self.flat_eps_max,
            "round_eps2_tol": self.round_eps2_tol,
            "round_axis_ratio_tol": self.round_axis_ratio_tol,
            "max_tilt_deg": self.max_tilt_deg,
            "min_part_scale_m": self.min_part_scale_m,
            "level_max_angle_deg": self.level_max_angle_deg,
            "pinch_max_lift_m": self.pinch_max_lift_m,
            "opening_margin_m": self.opening_margin_m,
            "support_min_points": self.support_min_points,
            "support_min_fraction": self.support_min_fraction,
            "support_max_tilt_deg": self.support_max_tilt_deg,
            "unseen_incidence_deg": self.unseen_incidence_deg,
            "unseen_max_down_deg": self.unseen_max_down_deg,
            "approach_distance_m": self.approach_distance_m,
            "table_clearance_m": self.table_clearance_m,
            "max_obstacle_points": self.max_obstacle_points,
            "body_margin_m": self.body_margin_m,
            "body_carve_margin_m": self.body_carve_margin_m,
        }
        for key, value in non_negative.items():
            if not value >= 0:
                raise ValueError(f"grasp.{key} must be >= 0, got {value}")


@dataclass(frozen=True)
class PlannerConfig:
    """The planner's sections, with the paper's values set for every addition switched off."""

    cleaning: CleaningConfig = field(default_factory=CleaningConfig)
    recovery: RecoveryConfig = field(default_factory=RecoveryConfig)
    grasp: GraspConfig = field(default_factory=GraspConfig)
    additions: AdditionsConfig = field(default_factory=AdditionsConfig)

    def __post_init__(self) -> None:
        for name in self.additions.off():
            addition = ADDITIONS[name]
            section = getattr(self, addition.section)
            object.__setattr__(
                self, addition.section, dataclasses.replace(section, **addition.paper)
            )

    def with_additions(self, additions: AdditionsConfig) -> PlannerConfig:
        """This config with other switches (switching one back on does not restore a value
        that an off switch replaced: start from the file's config for that)."""
        return dataclasses.replace(self, additions=additions)


def load_planner_config(path: str | Path | None = "planner") -> PlannerConfig:
    """Load ``configs/planner.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(PlannerConfig, path)


def resolve_config(config: PlannerConfig | str | Path | None) -> PlannerConfig:
    """A :class:`PlannerConfig` from an instance, a config name or path; None -> planner.yaml.

    Files are parsed once per modification time (planning many clouds re-reads nothing).
    """
    if isinstance(config, PlannerConfig):
        return config
    return load_cached(load_planner_config, "planner" if config is None else config)
