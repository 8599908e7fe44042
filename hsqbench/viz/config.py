"""Settings of the Rerun episode recording (``configs/viewer.yaml``, reasons there)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from hsqbench.config import load_config


@dataclass(frozen=True)
class ViewerConfig:
    """What a :class:`~hsqbench.viz.rerun_recorder.RerunRecorder` logs and how finely.

    Attributes:
        step_interval_s: simulated seconds between two logged body poses.
        geom_groups: MuJoCo geom groups drawn as the scene and the bodies' looks.
        collision_geoms: also log the collision geoms (group 3) under ``.../collision_geoms``.
        max_faces_per_geom: untextured mesh geoms are decimated to at most this many triangles.
        depth_unit_m: depth images are stored as uint16 multiples of this, metres.
        cloud_radius_m, inlier_radius_m: point radii of the cloud and of the superquadrics'
            inlier points, metres.
        superquadric_mesh_quarter: ``Superquadric.to_mesh`` steps per quarter arc.
        candidate_length_m, candidate_radius_m: arrow drawn for each candidate, metres.
        max_candidates: most candidates logged per class (kept, and each rejection reason).
        max_inliers: most inlier points logged per hidden superquadric.
        top_grasps: number of best grasps drawn as outlines after planning.
        stem_length_m, outline_radius_m: gripper outline geometry, metres.
    """

    step_interval_s: float = 0.04
    geom_groups: tuple[int, ...] = (0, 1, 2)
    collision_geoms: bool = False
    max_faces_per_geom: int = 3000
    depth_unit_m: float = 0.0001
    cloud_radius_m: float = 0.001
    inlier_radius_m: float = 0.0012
    superquadric_mesh_quarter: int = 12
    candidate_length_m: float = 0.02
    candidate_radius_m: float = 0.0004
    max_candidates: int = 20000
    max_inliers: int = 1500
    top_grasps: int = 5
    stem_length_m: float = 0.05
    outline_radius_m: float = 0.001

    def __post_init__(self) -> None:
        if not self.step_interval_s > 0:
            raise ValueError(f"viewer.step_interval_s must be > 0 s, got {self.step_interval_s}")
        for name in (
            "depth_unit_m",
            "cloud_radius_m",
            "inlier_radius_m",
            "candidate_length_m",
            "candidate_radius_m",
            "stem_length_m",
            "outline_radius_m",
        ):
            if not getattr(self, name) > 0:
                raise ValueError(
                    f"viewer.{name} must be a positive length, got {getattr(self, name)}"
                )
        if self.superquadric_mesh_quarter < 2:
            raise ValueError("viewer.superquadric_mesh_quarter must be >= 2")
        if self.max_faces_per_geom < 12:
            raise ValueError("viewer.max_faces_per_geom must be >= 12 (a box)")
        if self.max_candidates < 1 or self.max_inliers < 1 or self.top_grasps < 0:
            raise ValueError(
                "viewer.max_candidates and viewer.max_inliers must be >= 1, viewer.top_grasps >= 0"
            )


def load_viewer_config(path: str | Path | None = "viewer") -> ViewerConfig:
    """Load ``configs/viewer.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(ViewerConfig, path)
