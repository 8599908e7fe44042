"""Example superquadrics shared by the tests of hsqbench.superquadric."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from hsqbench.superquadric.geometry import Superquadric

# (eps1, eps2, scale in metres): sphere, near-cube, cylinder, octahedron, pinched, extremes.
SHAPES = {
    "sphere": (1.0, 1.0, (0.04, 0.04, 0.04)),
    "ellipsoid": (1.0, 1.0, (0.015, 0.05, 0.03)),
    "cube": (0.1, 0.1, (0.03, 0.04, 0.05)),
    "cylinder": (0.1, 1.0, (0.03, 0.03, 0.05)),
    "octahedron": (2.0, 2.0, (0.04, 0.04, 0.04)),
    "octahedron_aniso": (2.0, 2.0, (0.02, 0.04, 0.05)),
    "pinched": (1.5, 1.5, (0.04, 0.03, 0.05)),
    "star_prism": (0.2, 1.8, (0.03, 0.04, 0.05)),
    "pinched_box": (1.8, 0.2, (0.03, 0.04, 0.05)),
    "eps_min": (0.05, 0.05, (0.05, 0.03, 0.04)),
    "eps_min_max": (0.05, 2.0, (0.03, 0.03, 0.06)),
    "bipyramid": (2.0, 0.05, (0.076, 0.047, 0.06)),
}


def random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return Rotation.random(random_state=rng).as_matrix(), rng.uniform(-0.5, 0.5, 3)


def make(name: str, rng: np.random.Generator | None = None) -> Superquadric:
    e1, e2, scale = SHAPES[name]
    if rng is None:
        return Superquadric(e1, e2, scale)
    rotation, translation = random_pose(rng)
    return Superquadric(e1, e2, scale, rotation, translation)
