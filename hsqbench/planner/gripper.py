"""The parallel-jaw gripper as stage two sees it: a closing line and three boxes.

The paper models the gripper by its jaw length ``l_j`` and maximum opening ``l_w``; collision
checks also need the volumes of the fingers and the palm. All are expressed in the grasp frame
(see :mod:`hsqbench.planner.grasp`): origin at the closing point P_G, x the closing axis, y the
third axis, z the approach axis pointing from the palm toward P_G. In that frame

- each finger is the box ``|x| in [w/2, w/2 + finger_thickness]``, ``|y| <= finger_width/2``,
  ``z in [-l_j, fingertip_overhang]`` for an opening ``w``;
- the palm is the box ``|x| <= palm_width/2``, ``|y| <= palm_thickness/2``,
  ``z in [-l_j - palm_depth, -l_j]``.

Any parallel-jaw gripper is described by the same nine numbers (``configs/gripper.yaml``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from hsqbench.config import load_cached, load_config


@dataclass(frozen=True)
class GripperModel:
    """Dimensions of a parallel-jaw gripper, all in metres (defaults: the Franka Hand).

    Attributes:
        name: a label.
        max_opening_m: ``l_w``, the largest distance between the finger pads.
        jaw_length_m: ``l_j``, from the closing line back to the palm face.
        fingertip_overhang_m: how far the fingertips reach past the closing line.
        finger_width_m: finger extent along the third axis.
        finger_thickness_m: finger extent along the closing axis, from the pad face outward.
        palm_width_m, palm_thickness_m, palm_depth_m: palm extents along the closing, third
            and approach axes.
        tcp_offset_m: distance from the flange (the hand's mounting frame) to P_G along the
            approach axis; the harness uses it to turn a grasp into a hand pose.
    """

    name: str = "franka_hand"
    max_opening_m: float = 0.08
    jaw_length_m: float = 0.0374
    fingertip_overhang_m: float = 0.0089
    finger_width_m: float = 0.021
    finger_thickness_m: float = 0.0264
    palm_width_m: float = 0.2044
    palm_thickness_m: float = 0.0633
    palm_depth_m: float = 0.0919
    tcp_offset_m: float = 0.1034

    def __post_init__(self) -> None:
        sizes = {
            "max_opening_m": self.max_opening_m,
            "jaw_length_m": self.jaw_length_m,
            "finger_width_m": self.finger_width_m,
            "finger_thickness_m": self.finger_thickness_m,
            "palm_width_m": self.palm_width_m,
            "palm_thickness_m": self.palm_thickness_m,
            "palm_depth_m": self.palm_depth_m,
        }
        for key, value in sizes.items():
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"gripper {key} must be a positive length in metres, got {value}")
        if not (np.isfinite(self.fingertip_overhang_m) and self.fingertip_overhang_m >= 0):
            raise ValueError(
                f"gripper fingertip_overhang_m must be >= 0, got {self.fingertip_overhang_m}"
            )
        if self.palm_width_m < self.max_opening_m + 2 * self.finger_thickness_m:
            raise ValueError(
                "gripper palm_width_m must cover both open fingers "
                f"(>= max_opening_m + 2 finger_thickness_m = "
                f"{self.max_opening_m + 2 * self.finger_thickness_m:.4f} m), got {self.palm_width_m}"
            )

    def boxes(self, opening_m: float | None = None, palm_extension_m: float = 0.0) -> NDArray:
        """The gripper's boxes in the grasp frame, shape (3, 2, 3): ``[finger+x, finger-x, palm]``.

        Each box is ``[lower corner, upper corner]``. ``opening_m`` defaults to ``l_w``;
        ``palm_extension_m`` lengthens the palm backwards (away from P_G) to cover the volume the
        hand sweeps on a straight approach of that length.
        """
        w = self.max_opening_m if opening_m is None else float(opening_m)
        x_in, x_out = w / 2, w / 2 + self.finger_thickness_m
        fy, py = self.finger_width_m / 2, self.palm_thickness_m / 2
        z_palm = -self.jaw_length_m
        finger_z = (z_palm, self.fingertip_overhang_m)
        return np.array(
            [
                [[x_in, -fy, finger_z[0]], [x_out, fy, finger_z[1]]],
                [[-x_out, -fy, finger_z[0]], [-x_in, fy, finger_z[1]]],
                [
                    [-self.palm_width_m / 2, -py, z_palm - self.palm_depth_m - palm_extension_m],
                    [self.palm_width_m / 2, py, z_palm],
                ],
            ]
        )


def load_gripper(name_or_path: str | Path = "gripper") -> GripperModel:
    """Load a gripper from ``configs/<name>.yaml`` (or a YAML path)."""
    return load_config(GripperModel, name_or_path)


def resolve_gripper(name_or_path: str | Path) -> GripperModel:
    """The gripper of ``configs/<name>.yaml`` (or a YAML path), parsed once per modification."""
    return load_cached(load_gripper, name_or_path)
