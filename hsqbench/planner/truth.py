"""Simulator truth about a scene's objects, for the privileged oracle planner only.

No perceiving planner is given this: the trial runner fills ``PlanningContext.truth`` only for
planners that declare ``privileged = True`` (:mod:`hsqbench.planner.oracle`), and to decide
whether a presentation is graspable at all.

Objects are given as the convex hulls MuJoCo collides with, in the world frame, so the oracle's
contacts and collisions are those of the simulation.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull


@dataclass(frozen=True, eq=False)
class ObjectTruth:
    """One object's collision hulls in the world frame.

    Attributes:
        name: the object's name.
        hulls: one (V, 3) vertex array per convex hull, world metres.
        friction: the sliding friction coefficient of its geoms (None: not known, e.g. a scene
            made outside the simulator; the contact then has the pads' friction).
    """

    name: str
    hulls: tuple[NDArray[np.float64], ...]
    friction: float | None = None

    def __post_init__(self) -> None:
        if not self.hulls:
            raise ValueError(f"{self.name}: an object needs at least one hull")
        for h in self.hulls:
            if h.ndim != 2 or h.shape[1] != 3 or h.shape[0] < 4 or not np.isfinite(h).all():
                raise ValueError(f"{self.name}: hulls must be (V >= 4, 3) finite vertex arrays")

    @functools.cached_property
    def facets(self) -> list[tuple[NDArray[np.float64], NDArray[np.float64]]]:
        """Per hull: triangles (T, 3, 3) and outward half-space equations (T, 4), ``n.x + d``."""
        out = []
        for h in self.hulls:
            hull = ConvexHull(h)
            out.append((h[hull.simplices], hull.equations))
        return out

    def inside(self, points: NDArray, margin_m: float = 0.0) -> NDArray[np.bool_]:
        """(N,) whether each point lies inside some hull by at least ``margin_m``."""
        points = np.asarray(points, float)
        out = np.zeros(points.shape[0], dtype=bool)
        for _, eq in self.facets:
            out |= np.all(points @ eq[:, :3].T + eq[:, 3] <= -margin_m, axis=1)
        return out


@dataclass(frozen=True, eq=False)
class HandTruth:
    """The hand's collision geometry in the TCP frame (x closing, from the right finger toward
    the left; z approach, from the palm toward the fingertips), as MuJoCo collides with it.

    Attributes:
        left_finger: (V, 3) vertices of the left finger's collision hulls (its mesh and pads),
            placed with the pad face on x = 0: at an opening ``w`` it lies at ``+w / 2`` in x.
        right_finger: the same for the right finger, extending toward -x (at ``-w / 2``).
        palm: (V, 3) vertices of the hand body's collision hull.
        pad_z_m: (lowest, highest) z of the pad faces: where along the approach axis a contact
            can sit on a pad.
        pad_friction: the pads' sliding friction coefficient.
    """

    left_finger: NDArray[np.float64]
    right_finger: NDArray[np.float64]
    palm: NDArray[np.float64]
    pad_z_m: tuple[float, float]
    pad_friction: float

    def __post_init__(self) -> None:
        for part in (self.left_finger, self.right_finger, self.palm):
            if part.ndim != 2 or part.shape[1] != 3 or not np.isfinite(part).all():
                raise ValueError("hand parts must be (V, 3) finite vertex arrays")
        if not (self.pad_z_m[0] < self.pad_z_m[1] and self.pad_friction > 0):
            raise ValueError("hand: pad_z_m must be (low, high) and pad_friction positive")

    def contact_friction(self, obj: ObjectTruth) -> float:
        """A pad's contact with ``obj``: MuJoCo takes the larger of the two geoms' sliding
        friction (equal priorities, the default; mujoco.readthedocs.io, Contact parameters)."""
        return max(self.pad_friction, obj.friction or 0.0)


@dataclass(frozen=True, eq=False)
class SceneTruth:
    """The objects on the table now (removed and cleared ones left out).

    Attributes:
        objects: their hulls.
        support_plane: the table ``(a, b, c, d)``, unit normal up.
        seed: the presentation's seed for the oracle's sampling, so that the graspability check
            and the oracle planner search the same samples of the same presentation.
        hand: the robot's hand (None: a scene made outside the simulator; the oracle then
            reads the Panda of ``configs/robot.yaml``, :func:`hsqbench.sim.scene_truth.panda_hand`).
    """

    objects: tuple[ObjectTruth, ...]
    support_plane: tuple[float, float, float, float]
    seed: int = 0
    hand: HandTruth | None = None

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)
