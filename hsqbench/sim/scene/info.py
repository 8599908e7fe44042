"""What a built scene holds: :class:`SceneInfo` and the names the harness reads."""

from __future__ import annotations

from dataclasses import dataclass, field

import mujoco
import numpy as np

KINDS = ("isolated", "packed", "pile")
INITIAL_KEY = "initial"
OBJECT_PREFIX = "obj/"
BIN_GEOMS = tuple(f"bin/{p}" for p in ("bottom", "wall_x-", "wall_x+", "wall_y-", "wall_y+"))


@dataclass(frozen=True)
class DepthCamera:
    """A depth camera of the scene: MuJoCo camera name, image size, field of view and range."""

    name: str
    width_px: int
    height_px: int
    fovy_deg: float
    min_range_m: float
    max_range_m: float


@dataclass
class SceneInfo:
    """What a built scene contains. Lengths in metres, world frame (= robot base frame).

    Attributes:
        kind, seed: how the scene was drawn.
        objects: names of the placed objects, in draw order.
        object_bodies: object name -> body name; ``object_body_ids``: -> body id.
        object_geom_ids: object name -> ids of its collision geoms.
        initial_poses: object name -> (7,) settled pose (x, y, z, qw, qx, qy, qz).
        depth_cameras: the two depth cameras; ``viewer_camera``: camera name for pictures.
        table_top_z: height of the table top; ``support_plane``: (a, b, c, d) with
            a x + b y + c z + d = 0 on the table top and (a, b, c) pointing up.
        table_geom_id: the table top's geom id.
        workspace_min, workspace_max: (3,) corners of the placement region (z from the table top).
        bin_min, bin_max: (3,) corners of the bin's inside; ``bin_geom_ids``: its geoms.
        robot_prefix, arm_joints, arm_actuators, finger_joints, gripper_actuator, tcp_site,
            hand_body: names of the robot's elements (see :class:`hsqbench.sim.robot.Panda`).
        initial_key: keyframe name of the settled state (``mj_resetDataKeyframe``).
        settle_time_s: simulated time the settling took; ``max_speed_after_settle``: largest
            object speed (m/s or rad/s) at its end.
        build_time_s: wall-clock time of :func:`build_scene`.
        resting_poses: object name -> index of the resting pose drawn
            (:func:`hsqbench.assets.resting.resting_poses`, most probable first), -1 upright
            (and in piles, whose objects fall in whatever pose they land).
        rejected_drops: piles only: why earlier drops of the scene's generator were rejected
            (did not settle, an object off the table or outside the workspace), in order.
    """

    kind: str
    seed: int
    objects: list[str]
    object_bodies: dict[str, str]
    object_body_ids: dict[str, int]
    object_geom_ids: dict[str, np.ndarray]
    initial_poses: dict[str, np.ndarray]
    depth_cameras: tuple[DepthCamera, ...]
    viewer_camera: str
    table_top_z: float
    support_plane: np.ndarray
    table_geom_id: int
    workspace_min: np.ndarray
    workspace_max: np.ndarray
    bin_min: np.ndarray
    bin_max: np.ndarray
    bin_geom_ids: np.ndarray
    robot_prefix: str
    arm_joints: tuple[str, ...]
    arm_actuators: tuple[str, ...]
    finger_joints: tuple[str, ...]
    gripper_actuator: str
    tcp_site: str
    hand_body: str
    initial_key: str = INITIAL_KEY
    settle_time_s: float = 0.0
    max_speed_after_settle: float = 0.0
    build_time_s: float = 0.0
    resting_poses: dict[str, int] = field(default_factory=dict)
    rejected_drops: list[str] = field(default_factory=list)

    @property
    def camera_names(self) -> tuple[str, ...]:
        return tuple(c.name for c in self.depth_cameras)

    def reset(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Return ``data`` to the settled initial state."""
        mujoco.mj_resetDataKeyframe(model, data, model.key(self.initial_key).id)
        mujoco.mj_forward(model, data)
