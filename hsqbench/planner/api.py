"""The planner interface the harness calls: the contract every planner shares.

- :class:`PlanningContext`: what the harness knows besides the cloud (table plane, packed scene,
  seed, cameras, workspace).
- :class:`Planner`: the protocol every planner implements, ``plan(points, context)``; baselines
  and users' planners plug in the same way (see :mod:`hsqbench.planner.registry`).
- :class:`PlanResult`: ranked grasps plus everything needed to explain them.
- :func:`validate_cloud`, :func:`validate_cameras`, :func:`validate_plane`: the checks of the
  inputs every planner gets.

The paper's planner behind this contract is :mod:`hsqbench.planner.hsq`.

Support plane convention: ``(a, b, c, d)`` with ``a x + b y + c z + d = 0`` and ``(a, b, c)`` the
unit normal pointing to the free side (up, for a table).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.grasp import Grasp
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet
from hsqbench.superquadric.primitives import as_points


def validate_cloud(points: ArrayLike) -> NDArray[np.float64]:
    """The cloud as (N, 3) float64, or a ValueError naming the problem and the fix."""
    try:
        cloud = as_points(points)
    except ValueError as exc:
        raise ValueError(f"the point cloud must be an (N, 3) array of metres: {exc}") from None
    if cloud.shape[0] == 0:
        raise ValueError("the point cloud is empty; the planner needs the points of the object(s)")
    finite = np.isfinite(cloud).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        raise ValueError(
            f"the point cloud has {bad.size} row(s) with NaN or inf (first at index {bad[0]}); "
            "drop them first, e.g. points[np.isfinite(points).all(axis=1)]"
        )
    return cloud


def validate_cameras(cameras: ArrayLike | None) -> NDArray[np.float64] | None:
    """Camera centres as (C, 3) float64, or a ValueError naming the problem."""
    if cameras is None:
        return None
    arr = np.asarray(cameras, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(
            f"camera_positions must be a (C, 3) array of finite metres, got shape {arr.shape}"
        )
    return arr


def validate_plane(plane: ArrayLike | None) -> NDArray[np.float64] | None:
    """``(a, b, c, d)`` scaled so that ``(a, b, c)`` is a unit normal; ValueError if impossible."""
    if plane is None:
        return None
    arr = np.asarray(plane, dtype=np.float64).reshape(-1)
    if arr.shape != (4,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"support_plane must be 4 finite numbers (a, b, c, d), got {plane!r}")
    norm = float(np.linalg.norm(arr[:3]))
    if norm < 1e-9:
        raise ValueError(f"support_plane normal (a, b, c) must not be zero, got {plane!r}")
    return arr / norm


@dataclass(frozen=True)
class PlanningContext:
    """What a planner may use besides the cloud.

    Attributes:
        support_plane: the table ``(a, b, c, d)`` (unit normal toward the free side), or None.
        packed: several objects in the cloud (the paper then drops ``h_delta``).
        seed: for any randomness in the planner; None means the planner's default.
        camera_positions: (C, 3) camera centres, world metres, if known (the hsq planner waives
            the support test at contacts none of them can see).
        workspace_bounds: ``(lower (3,), upper (3,))`` corners of the workspace box, metres, if
            known (ignored by the hsq planner).
        truth: simulator truth (:class:`~hsqbench.planner.truth.SceneTruth`), given only to
            planners that declare ``privileged = True`` (the oracle); None for every other.
        scene: the scene kind, ``isolated``, ``packed`` or ``pile``, if known (the vgn and
            giga planners pick their weights by it).
        depth_views: the depth images the cloud was made from, if known: objects with
            ``depth_m`` (H, W), ``K`` (3, 3) and ``T_world_camera`` (4, 4)
            (:class:`~hsqbench.sim.perceived.CameraView`; the vgn and giga planners read them).
    """

    support_plane: tuple[float, float, float, float] | None = None
    packed: bool = False
    seed: int | None = None
    camera_positions: NDArray[np.float64] | None = None
    workspace_bounds: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
    truth: Any = None
    scene: str | None = None
    depth_views: tuple[Any, ...] | None = None

    def __post_init__(self) -> None:
        plane = validate_plane(self.support_plane)
        if plane is not None:
            object.__setattr__(self, "support_plane", tuple(float(x) for x in plane))


@runtime_checkable
class Planner(Protocol):
    """Anything that turns a cloud into ranked grasps."""

    name: str

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult: ...


@dataclass
class PlanResult:
    """The outcome of planning on one cloud.

    Attributes:
        grasps: surviving grasps, best first (ties, e.g. the rolls of one closing line, keep
            candidate order); for the hsq planner a lazy :class:`RankedGrasps` sequence.
        hidden_superquadrics: stage one's output (``HiddenSuperquadric`` objects), if any.
        candidates: every candidate with ``rejected_by``, ``scores``, ``factors`` and
            ``measures`` (None for planners without candidates).
        remaining: candidates left after each step, in order: ``synthesised``, then one entry
            per elimination rule (see :data:`~hsqbench.planner.hsq.stage_two.candidates.REJECTION_REASONS`).
        removed_by: how many candidates each rule removed.
        timings: wall-clock seconds per stage (``cleaning``, ``recovery``, ``synthesis``,
            ``elimination``, ``scoring``, ``total``).
        reason: why no grasp survived, in words; ``""`` when there are grasps.
        planner: the planner's name.
        n_removed: input points the planner discarded before planning (the hsq planner's
            cleaning of isolated points, :mod:`hsqbench.planner.cleaning`).
        surface_points: (N, 3) the planner's own surface model as points, world metres, for
            display (the vgn and giga planners' TSDF zero crossings); None for the others.
    """

    grasps: Sequence[Grasp]
    hidden_superquadrics: list[Any] = field(default_factory=list)
    candidates: CandidateSet | None = None
    remaining: dict[str, int] = field(default_factory=dict)
    removed_by: dict[str, int] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    reason: str = ""
    planner: str = "hsq"
    n_removed: int = 0
    surface_points: NDArray[np.float64] | None = None

    @property
    def best(self) -> Grasp | None:
        return self.grasps[0] if self.grasps else None

    def to_dict(self, top: int | None = None) -> dict[str, Any]:
        """JSON-ready summary: the ``top`` best grasps (all if None), counts, timings, reason."""
        grasps = self.grasps if top is None else self.grasps[:top]
        return {
            "planner": self.planner,
            "n_grasps": len(self.grasps),
            "grasps": [g.to_dict() for g in grasps],
            "hidden_superquadrics": [_hidden_to_dict(h) for h in self.hidden_superquadrics],
            "remaining": dict(self.remaining),
            "removed_by": dict(self.removed_by),
            "timings": dict(self.timings),
            "reason": self.reason,
            "n_removed": self.n_removed,
        }


def _hidden_to_dict(hidden: Any) -> dict[str, Any]:
    sq = hidden.superquadric
    return {
        "eps1": sq.eps1,
        "eps2": sq.eps2,
        "scale": sq.scale.tolist(),
        "rotation": sq.rotation.tolist(),
        "translation": sq.translation.tolist(),
        "n_inliers": len(hidden.inliers),
        "alpha": float(hidden.alpha),
        "beta": float(hidden.beta),
    }
