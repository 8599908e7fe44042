"""Closing lines near the table, levelled and lifted (our addition to the paper's synthesis).

The paper's candidates follow the hidden superquadric's axes exactly. For an object lying on the
table (a banana, a hammer or screwdriver handle, 2-4 cm thick) the only grasp is from above with
the closing line nearly parallel to the table, and two details of the fit then decide whether the
fingers, which reach ``fingertip_overhang_m`` (9 mm) past the closing line, clear the table:

- *tilt*: a fit to a partly seen object tilts its axes by several degrees; with the fingers open
  to the approach width (the contacts plus 1 cm), an 8 degree tilt lowers the outer edge of the
  lower finger by ~8 mm (measured: the banana's best line, 19 mm above the table);
- *height*: the closing line of a hidden superquadric passes through its centre, which for a
  fit to the seen upper part of a thin object can sit 1 cm above the table: the fingertips then
  cross it even from straight above.

Repair, only for a line that the table rule would remove at every roll and whose direction is
within ``level_max_angle_deg`` of the table plane: its direction is projected onto the plane
(levelled),
it is raised along the table normal just enough for the fingertips to stay
``table_clearance_m`` above the table when approaching straight down (lifted), its contacts are
found again on its superquadric (both ways from the raised point, so ``P_G`` is re-centred), and
``approach0`` becomes the downward normal, so roll 0 is the straight top-down approach. The
repaired line replaces the original (family ``levelled``) if it is still antipodal: its start
inside the superquadric and the surface normal at both contacts within ``max_tilt_deg`` of the
line, the test the paper's moved lines pass (:mod:`hsqbench.planner.hsq.stage_two.synthesis`). Every rule of
elimination then runs on it as on any line.

Pinch (``pinch_max_lift_m``): a part thinner than twice the fingertips' clearance (12 mm above
the table) has no antipodal line at the lifted height. A Franka hand then pinches it with the
lower ends of its pads: the contacts stay where the levelled line meets the superquadric, and
the line (the hand) is lifted by at most ``pinch_max_lift_m``, so the pads, 17 mm tall about the
line, still cover the part's side from 3 mm above the table up. Family ``pinched``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet
from hsqbench.planner.hsq.stage_two.elimination import approach_openings, line_boxes, table_clear
from hsqbench.planner.hsq.stage_two.shape_rows import ShapeRows
from hsqbench.superquadric.geometry import Superquadric

#: Family names of a repaired line (``ClosingLines.family``, ``Grasp.family``): levelled and
#: lifted, or levelled with only the hand lifted (a pinch, module docstring).
LEVELLED = "levelled"
PINCHED = "pinched"
#: Extra lift beyond the exact clearance, metres: the repaired line must pass the table rule's
#: ``>=`` test despite float rounding.
_LIFT_SLACK_M = 1e-5


def level_table_lines(
    cands: CandidateSet,
    superquadrics: Sequence[Superquadric],
    plane: NDArray,
    gripper: GripperModel,
    config: GraspConfig,
) -> NDArray[np.int64]:
    """Repair, in place, the lines of ``cands`` that the table blocks (module docstring).

    Args:
        cands: synthesised candidates (``lines.source`` indexes ``superquadrics``).
        plane: ``(a, b, c, d)``, ``(a, b, c)`` the unit normal toward the free side.

    Returns:
        The indices of the repaired lines.
    """
    L = cands.lines
    if len(L) == 0:
        return np.zeros(0, dtype=np.int64)
    normal, offset = np.asarray(plane[:3], float), float(plane[3])
    all_lines = np.arange(len(L))
    boxes = line_boxes(
        gripper, approach_openings(L.half_lengths, gripper, config), config.approach_distance_m
    )
    blocked = ~np.any(table_clear(cands, all_lines, boxes, plane, config.table_clearance_m), axis=1)
    along = L.directions @ normal
    idx = np.flatnonzero(
        blocked & (np.abs(along) <= np.sin(np.deg2rad(config.level_max_angle_deg)))
    )
    if idx.size == 0:
        return idx

    d = L.directions[idx] - along[idx, None] * normal
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    height = L.centres[idx] @ normal + offset
    need = gripper.fingertip_overhang_m + config.table_clearance_m + _LIFT_SLACK_M
    start = L.centres[idx] + np.maximum(need - height, 0.0)[:, None] * normal

    src = L.source[idx]
    rot = np.array([sq.rotation for sq in superquadrics]).reshape(-1, 3, 3)[src]
    trans = np.array([sq.translation for sq in superquadrics]).reshape(-1, 3)[src]
    shapes = ShapeRows.of(superquadrics, src)
    dl = np.einsum("nji,nj->ni", rot, d)
    cos_min = np.cos(np.deg2rad(config.max_tilt_deg))

    def contacts(points: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        """Whether a line from ``points`` along ``d`` is antipodal, and its two contacts."""
        o = np.einsum("nji,nj->ni", rot, points - trans)
        ok = shapes.inside_outside_pow(o) < 1.0
        t_pos = shapes.contact_distance(o, dl)
        t_neg = shapes.contact_distance(o, -dl)
        for t, sign in ((t_pos, 1.0), (t_neg, -1.0)):
            grad = shapes.gradient(o + sign * t[:, None] * dl)
            cos = sign * np.einsum("ij,ij->i", grad, dl) / np.linalg.norm(grad, axis=1)
            ok &= cos >= cos_min
        return ok, t_pos, t_neg

    ok, t_pos, t_neg = contacts(start)
    # Pinch: where the lifted line leaves the superquadric (a part thinner than the fingertips'
    # clearance) or its side, the contacts stay at the line's own height and only the hand is
    # lifted, so the pads hold the part with their lower ends (at most pinch_max_lift_m).
    lift = (start - L.centres[idx]) @ normal
    pinch = ~ok & (lift <= config.pinch_max_lift_m)
    if np.any(pinch):
        ok_low, t_pos_low, t_neg_low = contacts(L.centres[idx])
        pinch &= ok_low
        t_pos, t_neg = np.where(pinch, t_pos_low, t_pos), np.where(pinch, t_neg_low, t_neg)
        ok |= pinch
    idx, d, start, t_pos, t_neg, pinch = (x[ok] for x in (idx, d, start, t_pos, t_neg, pinch))
    L.centres[idx] = start + 0.5 * (t_pos - t_neg)[:, None] * d
    L.directions[idx] = d
    L.approach0[idx] = -normal
    L.half_lengths[idx] = 0.5 * (t_pos + t_neg)
    L.family[idx] = np.where(pinch, PINCHED, LEVELLED)
    return idx
