"""Our additions to the paper's planner, each behind a named switch (``additions:`` of
``configs/planner.yaml``), so that the paper's planner and every ablation are configs.

A switch that is on leaves its parameters as their sections set them; a switch that is off
forces the paper's values (:data:`ADDITIONS`), whatever the sections say. ``hsq-paper`` is the
planner with every switch off (the table rule stays: a real arm cannot enter the table), and
``hsq-no-<name>`` (``_`` written ``-``) the default planner with one switch off; both are
registered in :mod:`hsqbench.planner.registry` from this table.

Kept out of the table, as readings of the paper rather than additions: the units of the q's
(``alpha_unit_m``, the dimensionless ``gamma``), the K rule counted on 2 mm voxels (the paper's
sensor density), the fits' 4 mm voxel downsampling and EM with switching for the inference.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any


@dataclass(frozen=True)
class Addition:
    """One addition: the config section it acts on, the paper's values of its parameters, a
    sentence for reports, and the addition that takes its place wherever the harness plans
    (cameras known), if any: while that one is on, switching this one off changes no trial."""

    section: str
    paper: dict[str, Any]
    sentence: str
    superseded_by: str | None = None


#: Name -> the addition. The order is the planner's order (cleaning, stage one, stage two, then
#: the retry of both).
ADDITIONS: dict[str, Addition] = {
    "thinning": Addition(
        "cleaning",
        {"voxel_m": 0.0},
        "a cloud denser than 2 mm is thinned to 2 mm voxel centroids, so the cost stops growing",
    ),
    "outlier_removal": Addition(
        "cleaning",
        {"min_neighbours": 0},
        "isolated points (flying pixels) are removed before both stages",
    ),
    "object_split": Addition(
        "recovery",
        {"split_objects": False},
        "stage one runs on each object of a packed scene (its cloud's clusters), not on the scene",
    ),
    "extra_parts": Addition(
        "recovery",
        {"kmeans_parts_factor": 1.0},
        "1.5 K K-means parts instead of the paper's K, so a handle gets a seed of its own",
    ),
    "fit_dedup": Addition(
        "recovery",
        {"duplicate_iou": 2.0},  # no overlap reaches twice the union: every fit runs to its end
        "a hidden fit converging onto an earlier result is stopped",
    ),
    "multi_start": Addition(
        "recovery",
        {"start_eps": ((1.0, 1.0),)},
        "the whole-object fit starts from 3 shapes (x 3 axis orders), not the ellipsoid alone",
    ),
    "sigma_annealing": Addition(
        "recovery",
        {"hidden_sigma_decay": 0.0},
        "hidden-part fits anneal their noise level, so a seed grows along its part",
    ),
    "caps": Addition(
        "recovery",
        {"max_parts": 1_000_000, "max_surface_samples": 1_000_000_000},
        "caps on the number of parts and of surface samples bound the time on large scenes",
    ),
    "thin_parts": Addition(
        "grasp",
        {"min_part_scale_m": 0.0},
        "hidden superquadrics thinner than 5 mm (a single face of a body) get no closing lines",
    ),
    "slide_all_shapes": Addition(
        "grasp",
        {"slide_all_shapes": False},
        "every superquadric's lines slide (not only prisms' and boxes'), kept where antipodal",
    ),
    "antipodal_check": Addition(
        "grasp",
        {"max_tilt_deg": 90.0},
        "moved (slid, rotated, levelled) lines are kept only where the contacts stay antipodal",
    ),
    "table_lines": Addition(
        "grasp",
        {"level_table_lines": False},
        "lines the table blocks are levelled and lifted, so objects lying flat get grasps",
    ),
    "pinch": Addition(
        "grasp",
        {"pinch_max_lift_m": 0.0},
        "a part too thin for a lifted line is pinched with the pads' lower ends",
    ),
    "duplicate_lines": Addition(
        "grasp",
        {"duplicate_distance_m": 1e-9, "duplicate_angle_deg": 1e-9},
        "the same closing line from several fits is kept once (from the best fit)",
    ),
    "opening_margin": Addition(
        "grasp",
        {"opening_margin_m": 0.0},
        "contacts must be 4 mm narrower than the opening, for noise and fit error",
    ),
    "support_fraction": Addition(
        "grasp",
        {"support_min_fraction": 0.0},
        "kappa grows with the cloud's density (a tenth of a fully seen disc)",
    ),
    "support_facing": Addition(
        "grasp",
        {"support_max_tilt_deg": 90.0},
        "the support points must form a surface facing the finger (not an edge), where the"
        " hidden-body rule does not run (it needs the cameras)",
        superseded_by="hidden_bodies",
    ),
    "unseen_waiver": Addition(
        "grasp",
        {"unseen_incidence_deg": 180.0},
        "a contact no camera can see needs no support (the other one still does)",
    ),
    "sweep": Addition(
        "grasp",
        {"sweep_rule": False},
        "the open fingers and the palm's approach path must be free of cloud points",
    ),
    "hidden_bodies": Addition(
        "grasp",
        {"body_rule": False},
        "the hand must not enter the hidden superquadrics where no camera saw free space",
    ),
    "redraw": Addition(
        "recovery",
        {"no_grasp_redraws": 0},
        "when no grasp survives, both stages run again on new K-means parts (twice at most)",
    ),
}


@dataclass(frozen=True)
class AdditionsConfig:
    """One switch per entry of :data:`ADDITIONS` (True: ours, False: the paper's values)."""

    thinning: bool = True
    outlier_removal: bool = True
    object_split: bool = True
    extra_parts: bool = True
    fit_dedup: bool = True
    multi_start: bool = True
    sigma_annealing: bool = True
    caps: bool = True
    thin_parts: bool = True
    slide_all_shapes: bool = True
    antipodal_check: bool = True
    table_lines: bool = True
    pinch: bool = True
    duplicate_lines: bool = True
    opening_margin: bool = True
    support_fraction: bool = True
    support_facing: bool = True
    unseen_waiver: bool = True
    sweep: bool = True
    hidden_bodies: bool = True
    redraw: bool = True

    def __post_init__(self) -> None:
        for name in self.names():
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"additions.{name} must be true or false")

    @staticmethod
    def names() -> list[str]:
        return [f.name for f in fields(AdditionsConfig)]

    def off(self) -> list[str]:
        """The switches that are off."""
        return [n for n in self.names() if not getattr(self, n)]


def all_off() -> AdditionsConfig:
    """Every addition off: the paper's planner."""
    return AdditionsConfig(**dict.fromkeys(AdditionsConfig.names(), False))


def planner_name(addition: str) -> str:
    """``hsq-no-<addition>`` with ``-`` for ``_``."""
    return "hsq-no-" + addition.replace("_", "-")


def ablation_planners() -> dict[str, str]:
    """Planner name -> the addition it turns off, for every addition."""
    return {planner_name(name): name for name in AdditionsConfig.names()}
