"""One planned grasp of a parallel-jaw gripper, and the frame convention every planner shares.

Grasp frame (the only convention; the harness turns it into a hand pose):

- origin: the closing point ``P_G``, the midpoint of the two finger pads, in world metres;
- ``rotation[:, 0]``: the closing axis (the line joining the pads; its sign carries no meaning
  for a symmetric gripper);
- ``rotation[:, 2]``: the approach axis, pointing from the palm toward ``P_G``;
- ``rotation[:, 1]``: the third axis, ``approach x closing``, so the columns are right-handed.

For the MuJoCo Menagerie Franka hand (body ``hand``: y = finger sliding axis, z = approach) the
hand pose is ``R_hand = rotation @ [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]`` (hand x = -third,
hand y = closing, hand z = approach) and ``p_hand = position - tcp_offset * approach`` with
``tcp_offset = GripperModel.tcp_offset_m``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

#: Grasp frame -> Menagerie ``hand`` body frame: ``R_hand = rotation @ GRASP_TO_MENAGERIE_HAND``.
GRASP_TO_MENAGERIE_HAND = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


class InvalidGrasp(ValueError):
    """A :class:`Grasp` built with values its contract rules out (a NaN or infinite pose, a
    rotation that is not one, a negative width); a planner that builds one has failed
    (:mod:`hsqbench.planner.failure` names the planner's line that built it)."""


@dataclass(frozen=True)
class Grasp:
    """A grasp pose with its width, score and provenance.

    Attributes:
        position: ``P_G`` in world metres, shape (3,).
        rotation: 3x3 rotation, columns (closing axis, third axis, approach axis), world frame.
        width: distance between the two contacts along the closing axis, metres (the opening
            at which the pads touch the modelled surface).
        score: ``h`` in [0, 1]; the product of ``factors``.
        factors: the score factors by name (``h_alpha``, ``h_beta``, ``h_gamma`` and, unless the
            scene is packed, ``h_delta``); empty for planners that do not report them.
        source: index of the hidden superquadric that made the grasp (-1 if none).
        family: which candidate family produced it (``axis``, ``slide``, ``rotate``, ...).
        approach_width: the opening to approach with, metres: wider than ``width`` by a margin
            for noise and fit error. The planner checked collisions (object, neighbours, table)
            for the fingers at this opening, so open the gripper to it, not wider. NaN when the
            planner does not say (then the harness chooses).
    """

    position: NDArray[np.float64]
    rotation: NDArray[np.float64]
    width: float
    score: float
    factors: dict[str, float] = field(default_factory=dict)
    source: int = -1
    family: str = ""
    approach_width: float = float("nan")

    def __post_init__(self) -> None:
        try:
            position = np.asarray(self.position, dtype=np.float64).reshape(3)
            rotation = np.asarray(self.rotation, dtype=np.float64).reshape(3, 3)
            width, score = float(self.width), float(self.score)
        except (TypeError, ValueError) as exc:
            raise InvalidGrasp(
                "a grasp is a position of 3 numbers, a 3x3 rotation, a width in metres and a "
                f"score: {exc}"
            ) from None
        if not (np.all(np.isfinite(position)) and np.all(np.isfinite(rotation))):
            raise InvalidGrasp("grasp position and rotation must be finite")
        if np.max(np.abs(rotation.T @ rotation - np.eye(3))) > 1e-6 or (
            np.dot(np.cross(rotation[:, 0], rotation[:, 1]), rotation[:, 2]) < 0
        ):
            raise InvalidGrasp(
                "grasp rotation must be a proper rotation (columns closing, third, approach)"
            )
        if not (np.isfinite(width) and width >= 0):
            raise InvalidGrasp(f"grasp width must be a finite length >= 0 m, got {width}")
        object.__setattr__(self, "position", position)
        object.__setattr__(self, "rotation", rotation)
        if not (np.isnan(self.approach_width) or self.approach_width >= width):
            raise InvalidGrasp(
                f"grasp approach_width ({self.approach_width} m) must be at least its width "
                f"({self.width} m)"
            )
        object.__setattr__(self, "width", width)
        object.__setattr__(self, "approach_width", float(self.approach_width))
        object.__setattr__(self, "score", score)

    @property
    def closing_axis(self) -> NDArray[np.float64]:
        return self.rotation[:, 0]

    @property
    def approach_axis(self) -> NDArray[np.float64]:
        return self.rotation[:, 2]

    def contacts(self) -> NDArray[np.float64]:
        """The two modelled contact points ``P_G -/+ width/2 * closing``, shape (2, 3), metres."""
        offset = 0.5 * self.width * self.closing_axis
        return np.stack([self.position - offset, self.position + offset])

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready mapping (lists of floats)."""
        return {
            "position": self.position.tolist(),
            "rotation": self.rotation.tolist(),
            "width": self.width,
            "approach_width": None if np.isnan(self.approach_width) else self.approach_width,
            "score": self.score,
            "factors": dict(self.factors),
            "source": self.source,
            "family": self.family,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Grasp:
        """Inverse of :meth:`to_dict`."""
        return cls(
            position=np.asarray(data["position"]),
            rotation=np.asarray(data["rotation"]),
            width=data["width"],
            approach_width=float("nan")
            if data.get("approach_width") is None
            else float(data["approach_width"]),
            score=data["score"],
            factors={k: float(v) for k, v in data.get("factors", {}).items()},
            source=int(data.get("source", -1)),
            family=str(data.get("family", "")),
        )
