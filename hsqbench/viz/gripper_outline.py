"""A parallel-jaw gripper drawn as line strips at a grasp pose.

In the grasp frame (:mod:`hsqbench.planner.grasp`: x closing, y third, z approach from the palm
toward P_G) the outline lies in the plane y = 0 and has five strips:

- two finger rectangles, ``|x| in [w/2, w/2 + finger_thickness]``, ``z in [-l_j, overhang]``,
  for the opening ``w``;
- the palm rectangle, ``|x| <= palm_width/2``, ``z in [-l_j - palm_depth, -l_j]``;
- the approach stem from the back of the palm, ``stem`` further back along -z;
- the closing line between the two pads, ``x in [-w/2, w/2]`` at ``z = 0``.

The same boxes as :meth:`hsqbench.planner.gripper.GripperModel.boxes`, so what is drawn is what
the planner's collision test used. World points are ``p_world = R p + P_G``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.gripper import GripperModel


def _rectangle(x0: float, x1: float, z0: float, z1: float) -> NDArray[np.float64]:
    return np.array([[x0, 0, z0], [x1, 0, z0], [x1, 0, z1], [x0, 0, z1], [x0, 0, z0]], float)


def gripper_outline(
    gripper: GripperModel,
    position: ArrayLike,
    rotation: ArrayLike,
    opening_m: float,
    stem_length_m: float,
) -> list[NDArray[np.float64]]:
    """Line strips (each (K, 3), world metres) of the gripper at a grasp pose.

    Args:
        gripper: finger and palm sizes.
        position: (3,) ``P_G``; rotation: (3, 3) columns closing, third, approach.
        opening_m: distance between the finger pads (the grasp's width).
        stem_length_m: length of the approach stem behind the palm.
    """
    p = np.asarray(position, dtype=np.float64).reshape(3)
    r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    if not (np.isfinite(opening_m) and opening_m >= 0):
        raise ValueError(f"opening_m must be a finite width >= 0 m, got {opening_m}")
    half = 0.5 * float(opening_m)
    t, lj = gripper.finger_thickness_m, gripper.jaw_length_m
    z_tip, z_back = gripper.fingertip_overhang_m, -lj - gripper.palm_depth_m
    pw = 0.5 * gripper.palm_width_m
    local = [
        _rectangle(half, half + t, -lj, z_tip),
        _rectangle(-half - t, -half, -lj, z_tip),
        _rectangle(-pw, pw, z_back, -lj),
        np.array([[0.0, 0.0, z_back], [0.0, 0.0, z_back - stem_length_m]]),
        np.array([[-half, 0.0, 0.0], [half, 0.0, 0.0]]),
    ]
    return [s @ r.T + p for s in local]
