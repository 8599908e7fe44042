"""Grasp candidates of stage two: closing lines, each swept by rolls about itself.

Every candidate lies on a *closing line*: a segment through ``P_G`` (its centre) along the closing
axis ``d``, reaching the superquadric surface at ``P_G +/- h d``. The paper turns each line into a
set of poses by rotating the gripper about it; here the roll angle ``phi`` gives

    approach(phi) = cos(phi) e1 + sin(phi) e2,    e2 = d x e1,
    third(phi)    = approach(phi) x d,

so the rotation ``[d, third, approach]`` is right-handed (see :mod:`hsqbench.planner.grasp`).
Candidate ``i`` is line ``i // n_roll`` at roll ``i % n_roll``. Synthesis creates the lines,
elimination fills ``rejected_by`` and scoring fills ``scores`` and ``factors``; the whole set,
rejected candidates included, stays available for inspection (the viewer colours by reason).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import overload

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.grasp import Grasp

#: Elimination reasons, in the order the rules run; ``KEPT`` marks a surviving candidate.
KEPT = ""
REJECTION_REASONS = ("duplicate", "width", "support", "table", "collision", "sweep", "hidden")


@dataclass
class ClosingLines:
    """Closing lines in the world frame (L lines).

    Attributes:
        centres: (L, 3) ``P_G`` of each line, metres.
        directions: (L, 3) unit closing axes ``d``.
        approach0: (L, 3) unit ``e1``, the approach axis at roll 0 (perpendicular to ``d``).
        half_lengths: (L,) ``h``, distance from ``P_G`` to each contact, metres.
        source: (L,) index of the hidden superquadric the line belongs to.
        axis: (L,) local axis of that superquadric the line is parallel to (0, 1, 2), or -1 for
            lines rotated about the local z axis.
        family: (L,) how the line was made: ``axis`` (a principal axis), ``slide`` (shifted
            parallel to a principal axis), ``rotate`` (rotated about z through the centre) or
            ``rotate+slide``.
        openings: (L,) gripper opening on approach, metres (set by elimination; NaN before).
    """

    centres: NDArray[np.float64]
    directions: NDArray[np.float64]
    approach0: NDArray[np.float64]
    half_lengths: NDArray[np.float64]
    source: NDArray[np.int64]
    axis: NDArray[np.int64]
    family: NDArray[np.str_]
    openings: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if self.openings is None:
            self.openings = np.full(self.half_lengths.shape[0], np.nan)

    def __len__(self) -> int:
        return int(self.half_lengths.shape[0])

    @classmethod
    def empty(cls) -> ClosingLines:
        z3 = np.zeros((0, 3))
        zi = np.zeros(0, dtype=np.int64)
        return cls(z3, z3.copy(), z3.copy(), np.zeros(0), zi, zi.copy(), np.zeros(0, dtype="<U12"))

    @classmethod
    def concatenate(cls, parts: list[ClosingLines]) -> ClosingLines:
        if not parts:
            return cls.empty()
        return cls(
            *(
                np.concatenate([getattr(p, name) for p in parts])
                for name in (
                    "centres",
                    "directions",
                    "approach0",
                    "half_lengths",
                    "source",
                    "axis",
                    "family",
                    "openings",
                )
            )
        )

    @property
    def second(self) -> NDArray[np.float64]:
        """(L, 3) ``e2 = d x e1``: the approach axis at roll 90 degrees."""
        return np.cross(self.directions, self.approach0)


def roll_frames(
    directions: NDArray, approach0: NDArray, roll_angles: NDArray
) -> NDArray[np.float64]:
    """Grasp rotations for every line and roll: (L, R, 3, 3), columns closing, third, approach."""
    e2 = np.cross(directions, approach0)
    cos, sin = np.cos(roll_angles), np.sin(roll_angles)
    approach = cos[None, :, None] * approach0[:, None, :] + sin[None, :, None] * e2[:, None, :]
    closing = np.broadcast_to(directions[:, None, :], approach.shape)
    third = np.cross(approach, closing)
    return np.stack([closing, third, approach], axis=-1)


@dataclass
class CandidateSet:
    """All candidates: ``len(lines) * len(roll_angles)`` poses with their fate.

    Attributes:
        lines: the closing lines.
        roll_angles: (R,) roll angles about each line, radians.
        rejected_by: (N,) reason each candidate was eliminated (one of
            :data:`REJECTION_REASONS`), or ``""`` for survivors.
        scores: (N,) score ``h`` of survivors, NaN for eliminated candidates.
        factors: name -> (N,) score factors (``h_alpha``, ``h_beta``, ``h_gamma``, ``h_delta``),
            NaN for eliminated candidates.
        measures: name -> (N,) the raw measures behind the factors (``alpha_m``, ``beta``,
            ``gamma``, ``delta_m``), NaN for eliminated candidates.
    """

    lines: ClosingLines
    roll_angles: NDArray[np.float64]
    rejected_by: NDArray[np.str_] = field(init=False)
    scores: NDArray[np.float64] = field(init=False)
    factors: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    measures: dict[str, NDArray[np.float64]] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self)
        self.rejected_by = np.full(n, KEPT, dtype="<U12")
        self.scores = np.full(n, np.nan)

    def __len__(self) -> int:
        return len(self.lines) * int(self.roll_angles.shape[0])

    @property
    def n_roll(self) -> int:
        return int(self.roll_angles.shape[0])

    @property
    def line_index(self) -> NDArray[np.int64]:
        """(N,) line of each candidate."""
        return np.repeat(np.arange(len(self.lines)), self.n_roll)

    @property
    def roll_index(self) -> NDArray[np.int64]:
        """(N,) roll of each candidate."""
        return np.tile(np.arange(self.n_roll), len(self.lines))

    @property
    def kept(self) -> NDArray[np.bool_]:
        return self.rejected_by == KEPT

    @property
    def positions(self) -> NDArray[np.float64]:
        """(N, 3) ``P_G`` of every candidate, metres."""
        return np.repeat(self.lines.centres, self.n_roll, axis=0)

    @property
    def rotations(self) -> NDArray[np.float64]:
        """(N, 3, 3) rotation of every candidate (columns closing, third, approach)."""
        frames = roll_frames(self.lines.directions, self.lines.approach0, self.roll_angles)
        return frames.reshape(-1, 3, 3)

    @property
    def widths(self) -> NDArray[np.float64]:
        """(N,) contact separation ``2 h`` of every candidate, metres."""
        return np.repeat(2.0 * self.lines.half_lengths, self.n_roll)

    def counts_by_reason(self) -> dict[str, int]:
        """How many candidates each rule removed, plus ``kept``."""
        out = {
            reason: int(np.count_nonzero(self.rejected_by == reason))
            for reason in REJECTION_REASONS
        }
        out["kept"] = int(np.count_nonzero(self.kept))
        return out

    def ranked(self) -> RankedGrasps:
        """Surviving candidates as grasps, best score first (stable: ties keep candidate order)."""
        kept = np.flatnonzero(self.kept)
        return RankedGrasps(self, kept[np.argsort(-self.scores[kept], kind="stable")])

    def grasp(self, index: int) -> Grasp:
        """Candidate ``index`` as a :class:`Grasp` (its score is NaN if it was eliminated)."""
        line, roll = divmod(int(index), self.n_roll)
        d = self.lines.directions[line]
        e1 = self.lines.approach0[line]
        e2 = _cross(d, e1)
        phi = self.roll_angles[roll]
        approach = np.cos(phi) * e1 + np.sin(phi) * e2
        rotation = np.column_stack([d, _cross(approach, d), approach])
        return Grasp(
            position=self.lines.centres[line],
            rotation=rotation,
            width=2.0 * float(self.lines.half_lengths[line]),
            approach_width=float(self.lines.openings[line]),
            score=float(self.scores[index]),
            factors={k: float(v[index]) for k, v in self.factors.items()},
            source=int(self.lines.source[line]),
            family=str(self.lines.family[line]),
        )


def _cross(a: NDArray, b: NDArray) -> NDArray[np.float64]:
    """Cross product of two 3-vectors (np.cross is slow on single vectors)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


class RankedGrasps(Sequence[Grasp]):
    """Candidates ``indices`` of a :class:`CandidateSet` as a read-only sequence of grasps.

    A :class:`Grasp` is built when an item is read, so ranking thousands of survivors costs
    nothing until the harness looks at them.
    """

    def __init__(self, candidates: CandidateSet, indices: NDArray[np.int64]) -> None:
        self.candidates = candidates
        self.indices = np.asarray(indices, dtype=np.int64)

    def __len__(self) -> int:
        return int(self.indices.size)

    @overload
    def __getitem__(self, item: int) -> Grasp: ...

    @overload
    def __getitem__(self, item: slice) -> RankedGrasps: ...

    def __getitem__(self, item: int | slice) -> Grasp | RankedGrasps:
        if isinstance(item, slice):
            return RankedGrasps(self.candidates, self.indices[item])
        return self.candidates.grasp(int(self.indices[item]))

    def __repr__(self) -> str:
        return f"RankedGrasps({len(self)} grasps)"
