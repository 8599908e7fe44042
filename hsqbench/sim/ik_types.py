"""The IK's value types: its config, a TCP :class:`Pose`, and the answers
(:class:`IKSolution`, :class:`PathSolution`) of :class:`hsqbench.sim.ik.ArmIK`."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Rotation by pi about the TCP's approach axis: the other half of a parallel-jaw grasp.
FLIP_ABOUT_APPROACH = np.diag([-1.0, -1.0, 1.0])


@dataclass(frozen=True)
class IKConfig:
    """Settings of :class:`ArmIK` (reasons in ``configs/trial.yaml``).

    Attributes:
        position_tolerance_m: largest accepted TCP position error, metres.
        orientation_tolerance_deg: largest accepted TCP orientation error, degrees.
        converged_fraction: iterate until both errors are below this fraction of the tolerances.
        max_iterations: IK iterations per restart.
        max_step_rad: largest change of any joint in one iteration, rad.
        joint_limit_margin_rad: seeds start this far inside the joint limits, and a solution
            closer than half of it to a limit is refused (a folded arm at its limits tracks
            poorly).
        stall_iterations: stop when the error fell by less than 1 % over this many iterations.
        restarts: solves from different seeds before a pose is declared unreachable.
        max_blocked_restarts: stop after this many solutions that reach the pose with the hand
            (or link7) touching an obstacle.
        seed_spread_rad: standard deviation of the random seeds around the home posture, rad.
        seed_library_size: random postures drawn for the seed library (0: no library).
        library_seeds: library postures nearest the target tried as seeds.
        grasp_branches: distinct solutions of a grasp pose whose motion chains are tried.
        position_cost, orientation_cost: weights of the TCP pose error (per metre, per radian).
        posture_cost: weight of the pull toward the home posture (per radian).
        lm_damping: Levenberg-Marquardt damping of the frame task (scaled by the squared error).
        damping: LM damping on every degree of freedom (keeps the QP well posed).
        solver: QP solver for ``mink.solve_ik``.
        clearance_m: smallest accepted distance between the hand (fingers, link7) and the
            obstacles.
        link_clearance_m: smallest accepted distance between links 1-6 and the obstacles, also
            kept while iterating (mink's ``CollisionAvoidanceLimit``; 0 turns that off).
        link_detection_m: obstacles closer than this to a link are constrained.
        max_waypoint_jump_rad: largest joint change between successive waypoints of a line;
            a larger one means the solution jumped branches.
        line_refinements: times a line's sampling is doubled before a jump counts as a branch
            change.
        sweep_step_rad: sampling of planned motions (largest joint change between samples)
            when checking them against obstacles.
    """

    position_tolerance_m: float = 0.003
    orientation_tolerance_deg: float = 2.0
    converged_fraction: float = 0.25
    max_iterations: int = 60
    max_step_rad: float = 0.2
    joint_limit_margin_rad: float = 0.05
    stall_iterations: int = 8
    restarts: int = 8
    max_blocked_restarts: int = 2
    seed_spread_rad: float = 0.6
    seed_library_size: int = 20000
    library_seeds: int = 5
    grasp_branches: int = 3
    position_cost: float = 1.0
    orientation_cost: float = 0.5
    posture_cost: float = 0.001
    lm_damping: float = 0.01
    damping: float = 1e-6
    solver: str = "daqp"
    clearance_m: float = 0.002
    link_clearance_m: float = 0.005
    link_detection_m: float = 0.02
    max_waypoint_jump_rad: float = 0.35
    line_refinements: int = 2
    sweep_step_rad: float = 0.015

    def __post_init__(self) -> None:
        for name in (
            "position_tolerance_m",
            "orientation_tolerance_deg",
            "max_step_rad",
            "max_waypoint_jump_rad",
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f"ik.{name} must be positive, got {getattr(self, name)}")
        if not 0 < self.converged_fraction <= 1:
            raise ValueError(
                f"ik.converged_fraction must be in (0, 1], got {self.converged_fraction}"
            )
        if self.max_iterations < 1 or self.restarts < 1:
            raise ValueError("ik.max_iterations and ik.restarts must be at least 1")


@dataclass(frozen=True)
class Pose:
    """A rigid pose in the world frame: ``position`` (3,) metres, ``rotation`` (3, 3) whose
    columns are the frame's axes."""

    position: NDArray[np.float64]
    rotation: NDArray[np.float64]

    def __post_init__(self) -> None:
        p = np.asarray(self.position, dtype=float).reshape(3)
        r = np.asarray(self.rotation, dtype=float).reshape(3, 3)
        if not (np.all(np.isfinite(p)) and np.all(np.isfinite(r))):
            raise ValueError("pose position and rotation must be finite")
        if np.max(np.abs(r.T @ r - np.eye(3))) > 1e-6 or np.linalg.det(r) < 0:
            raise ValueError("pose rotation must be a proper rotation matrix")
        object.__setattr__(self, "position", p)
        object.__setattr__(self, "rotation", r)

    def moved(self, offset: ArrayLike) -> Pose:
        """The same orientation, translated by ``offset`` (3,) metres in the world frame."""
        return Pose(self.position + np.asarray(offset, dtype=float), self.rotation)

    def flipped(self) -> Pose:
        """Rotated by pi about its own z axis (the same parallel-jaw grasp)."""
        return Pose(self.position, self.rotation @ FLIP_ABOUT_APPROACH)


def rotation_angle_deg(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Geodesic angle between two rotation matrices, degrees."""
    c = 0.5 * (np.trace(a.T @ b) - 1.0)
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def line_poses(start: Pose, end_position: ArrayLike, n_segments: int) -> list[Pose]:
    """``n_segments + 1`` poses from ``start`` to ``end_position`` on a straight line, with the
    start's orientation (both ends included)."""
    if n_segments < 1:
        raise ValueError(f"a line needs at least one segment, got {n_segments}")
    end = np.asarray(end_position, dtype=float)
    s = np.linspace(0.0, 1.0, n_segments + 1)
    return [Pose((1 - t) * start.position + t * end, start.rotation) for t in s]


@dataclass
class IKSolution:
    """The answer for one target.

    Attributes:
        q: arm joint angles (7,), radians (the best found, also when not ``ok``).
        ok: within the tolerances and clear of obstacles.
        position_error_m, orientation_error_deg: TCP error of ``q``.
        clearance_m: distance to the obstacles of the robot part with the least margin over
            its required clearance, metres (capped at 5 cm).
        restarts: solves run.
        iterations: IK iterations over all restarts.
        reason: why it failed, in words (``""`` when ``ok``).
        alternatives: other acceptable solutions on other branches (``solve`` with
            ``closest_to``), nearest first.
    """

    q: NDArray[np.float64]
    ok: bool
    position_error_m: float
    orientation_error_deg: float
    clearance_m: float = float("inf")
    restarts: int = 0
    iterations: int = 0
    reason: str = ""
    alternatives: list[NDArray[np.float64]] = field(default_factory=list)


@dataclass
class PathSolution:
    """Joint waypoints (K, 7) for a sequence of TCP poses; ``ok`` when every one was solved."""

    q: NDArray[np.float64]
    ok: bool
    reason: str = ""
    solutions: list[IKSolution] = field(default_factory=list)
