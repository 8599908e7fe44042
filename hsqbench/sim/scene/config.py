"""The scene config (``configs/scene.yaml``): workspace, cameras, placement and piles."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from hsqbench.config import load_config


@dataclass(frozen=True)
class WorkspaceConfig:
    centre_xy_m: tuple[float, float] = (0.5, 0.0)
    size_m: tuple[float, float] = (0.36, 0.5)
    height_m: float = 0.3


@dataclass(frozen=True)
class DepthCameraConfig:
    """Which cameras of the world file are depth cameras, and their range (what MJCF cannot
    say); image size and field of view are the cameras' own (``resolution``, ``fovy``)."""

    names: tuple[str, ...] = ("cam_left", "cam_right")
    min_range_m: float = 0.5
    max_range_m: float = 3.86


@dataclass(frozen=True)
class ViewerCameraConfig:
    """The world file's camera for pictures."""

    name: str = "viewer"


@dataclass(frozen=True)
class PlacementConfig:
    """How objects are put on the table (reasons in ``configs/scene.yaml``).

    ``pose``: ``upright`` (the mesh's own up, the paper's protocol) or ``resting`` (one of the
    object's stable resting poses, drawn by probability, :mod:`hsqbench.assets.resting`; poses
    less likely than ``min_resting_probability`` are not drawn). Either way a random yaw and
    position follow.
    """

    n_packed: int = 5
    margin_m: float = 0.02
    max_tries_per_object: int = 300
    max_scene_attempts: int = 20
    drop_height_m: float = 0.002
    pose: Literal["upright", "resting"] = "upright"
    min_resting_probability: float = 0.01

    def __post_init__(self) -> None:
        if not 0.0 <= self.min_resting_probability < 1.0:
            raise ValueError(
                f"placement.min_resting_probability must be in [0, 1), got "
                f"{self.min_resting_probability}"
            )


@dataclass(frozen=True)
class PileConfig:
    """How a pile is made (reasons in ``configs/scene.yaml``): ``n_objects`` objects dropped one
    by one, each from a random orientation, into a box of inner size ``box_size_m`` centred on
    the workspace; each drop settles (up to ``settle_time_s``) before the next; then the walls
    are removed and the heap settles again. A pile whose final settling does not converge
    within ``settle_time_s``
    or whose objects do not all end at rest on the table inside the workspace is dropped again
    from the scene's own generator, up to ``max_drop_attempts`` times.

    ``drop_clearance_m``: the dropped object's lowest point this far above the highest point of
    the heap below it. ``max_orientation_tries``: random orientations drawn before giving up on
    one whose bounding box fits between the walls.
    """

    n_objects: int = 5
    box_size_m: tuple[float, float] = (0.3, 0.3)
    wall_height_m: float = 0.3
    wall_thickness_m: float = 0.02
    drop_clearance_m: float = 0.03
    settle_time_s: float = 3.0
    max_drop_attempts: int = 5
    max_orientation_tries: int = 200

    def __post_init__(self) -> None:
        if self.n_objects < 1:
            raise ValueError(f"pile.n_objects must be >= 1, got {self.n_objects}")
        if min(self.box_size_m) <= 0 or self.wall_height_m <= 0 or self.wall_thickness_m <= 0:
            raise ValueError(
                "pile.box_size_m, pile.wall_height_m and pile.wall_thickness_m must be positive, "
                f"got {self.box_size_m}, {self.wall_height_m}, {self.wall_thickness_m}"
            )
        if self.drop_clearance_m < 0 or self.settle_time_s <= 0:
            raise ValueError("pile.drop_clearance_m must be >= 0 and pile.settle_time_s > 0")
        if self.max_drop_attempts < 1 or self.max_orientation_tries < 1:
            raise ValueError("pile.max_drop_attempts and pile.max_orientation_tries must be >= 1")


@dataclass(frozen=True)
class SceneConfig:
    """``configs/scene.yaml``; see the comments there for every value's reason.

    ``world``: the static world's MJCF (table, bin, floor, lights, cameras), a name in
    ``scenes/`` or a path; see :func:`world_path`.
    """

    world: str = "world"
    workspace: WorkspaceConfig = field(default_factory=WorkspaceConfig)
    depth_cameras: DepthCameraConfig = field(default_factory=DepthCameraConfig)
    viewer_camera: ViewerCameraConfig = field(default_factory=ViewerCameraConfig)
    placement: PlacementConfig = field(default_factory=PlacementConfig)
    pile: PileConfig = field(default_factory=PileConfig)


def load_scene_config(path: str | Path | None = "scene") -> SceneConfig:
    """Load ``configs/scene.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(SceneConfig, path)
