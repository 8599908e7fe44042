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
    """

    name: str
    hulls: tuple[NDArray[np.float64], ...]

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
class SceneTruth:
    """The objects on the table now (removed and cleared ones left out).

    Attributes:
        objects: their hulls.
        support_plane: the table ``(a, b, c, d)``, unit normal up.
    """

    objects: tuple[ObjectTruth, ...]
    support_plane: tuple[float, float, float, float]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)
