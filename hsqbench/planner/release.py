"""Rule 7 of elimination (addition ``release``): the object must fall free when the hand opens.

The hand lets go by opening to ``l_w``. An object that has parts above both open fingers comes to
rest on them instead of falling (a tapered cup gripped just below a rim wider than the opening
hangs on the fingers by its rim), and withdrawing the hand drags it along. A part above one
finger only tips the object off it, or is freed by the withdrawal. The rule removes a pose when,
at the grasp, at least ``release_min_points`` cloud points above *each* open finger would land on
it falling straight down, from at most ``release_fall_m`` above.

In the grasp frame a finger at opening ``l_w`` is the box ``x in [l_w/2, l_w/2 + thickness]``
(mirrored for the other), ``|y| <= width/2``, ``z in [-l_j, overhang]``
(:class:`~hsqbench.planner.gripper.GripperModel`); a point hangs on it when the ray from it
along gravity (world ``-z``, or the support plane's normal reversed) meets the box (slab test).
Only points that can land on a finger at some roll are tested against every roll: horizontally
near the grasp, not far above it, and within the finger slabs along the closing line.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.candidates import CandidateSet
from hsqbench.planner.config import GraspConfig
from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.gripper import GripperModel

#: Lines per block of the (points x lines) pre-selection: bounds its memory (~10 MB a matrix).
_CHUNK = 512
#: (line, point) pairs per block of the roll tests: bounds their memory (~25 MB).
_CHUNK_PAIRS = 20_000


def open_finger_boxes(gripper: GripperModel) -> NDArray[np.float64]:
    """The two fingers at the full opening, grasp frame: (2, 2, 3) ``[finger+x, finger-x]``,
    each ``[lower, upper]``."""
    half = 0.5 * gripper.max_opening_m
    far = half + gripper.finger_thickness_m
    y = 0.5 * gripper.finger_width_m
    z_lo, z_hi = -gripper.jaw_length_m, gripper.fingertip_overhang_m
    return np.array([[[half, -y, z_lo], [far, y, z_hi]], [[-far, -y, z_lo], [-half, y, z_hi]]])


def _ray_hits_box(q: NDArray, v: NDArray, box: NDArray, reach: float) -> NDArray[np.bool_]:
    """Slab test: does ``q + t v``, ``0 <= t <= reach``, meet ``box`` ([lower, upper])? ``q``
    and ``v`` (..., 3) broadcast together."""
    lo, hi = box[0], box[1]
    flat = np.abs(v) < 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (lo - q) / v
        t2 = (hi - q) / v
    inside = (q >= lo) & (q <= hi)
    t_near = np.where(flat, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    t_far = np.where(flat, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    enter, leave = t_near.max(axis=-1), t_far.min(axis=-1)
    return (leave >= np.maximum(enter, 0.0)) & (enter <= reach)


def _falling_pairs(
    pts: NDArray, centres: NDArray, dirs: NDArray, up: NDArray, boxes: NDArray, reach: float
) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(line, point) pairs that can land on a finger of the line's grasp at some roll, as the
    line index and the point relative to ``P_G``. Every box lies within ``radius`` of ``P_G``,
    so a point falling onto one is horizontally within ``radius`` of it, at most ``reach``
    above it; along the line it moves by ``t (up . d)``, so it must start within that of a
    finger's slab ``|s| in [l_w/2, l_w/2 + thickness]``."""
    radius = float(np.linalg.norm(np.abs(boxes).max(axis=(0, 1))))
    lo_s, hi_s = boxes[0, 0, 0], boxes[0, 1, 0]
    height = pts @ up
    flat = pts - height[:, None] * up
    which, index = [], []
    for start in range(0, len(centres), _CHUNK):
        c, d = centres[start : start + _CHUNK], dirs[start : start + _CHUNK]
        s = np.abs(pts @ d.T - np.einsum("ij,ij->i", c, d))  # (P, l)
        drift = reach * np.abs(d @ up)
        rise = height[:, None] - c @ up
        c_flat = c - (c @ up)[:, None] * up
        gap2 = (flat**2).sum(1)[:, None] + (c_flat**2).sum(1) - 2.0 * flat @ c_flat.T
        ok = (s + drift >= lo_s) & (s - drift <= hi_s) & (gap2 <= radius**2)
        ok &= (rise >= -radius) & (rise <= reach + radius)
        p_i, l_i = np.nonzero(ok)
        which.append(l_i + start)
        index.append(p_i)
    which_a, index_a = np.concatenate(which), np.concatenate(index)
    return which_a, pts[index_a] - centres[which_a]


def hangs_on_both_fingers(
    points: NDArray,
    cands: CandidateSet,
    lines: NDArray[np.int64],
    gripper: GripperModel,
    config: GraspConfig,
    up: NDArray | None = None,
) -> NDArray[np.bool_]:
    """(len(lines), R): poses at which the object would rest on both open fingers (module
    docstring). ``up``: the unit vertical (the support plane's normal; default world z)."""
    n_roll = cands.n_roll
    out = np.zeros((lines.size, n_roll), dtype=bool)
    if lines.size == 0 or len(points) == 0:
        return out
    up = np.array([0.0, 0.0, 1.0]) if up is None else np.asarray(up, float)
    pts = voxel_downsample(np.asarray(points, float), config.release_voxel_m).points
    boxes = open_finger_boxes(gripper)
    reach = config.release_fall_m
    L = cands.lines
    centres, dirs = L.centres[lines], L.directions[lines]
    which, rel = _falling_pairs(pts, centres, dirs, up, boxes, reach)
    if which.size == 0:
        return out
    # The grasp frame at roll phi: closing d, approach cos(phi) a0 + sin(phi) e2, third
    # approach x d; so a vector's grasp coordinates need five dot products and the rolls.
    a0 = L.approach0[lines]
    e2 = np.cross(dirs, a0)
    basis = np.stack([dirs, a0, e2, np.cross(a0, dirs), np.cross(e2, dirs)], axis=1)  # (l, 5, 3)
    cos, sin = np.cos(cands.roll_angles), np.sin(cands.roll_angles)
    per_line = np.zeros((2, lines.size, n_roll), dtype=np.int64)
    for start in range(0, which.size, _CHUNK_PAIRS):
        w = which[start : start + _CHUNK_PAIRS]
        q = _in_grasp_frames(
            np.einsum("pkj,pj->pk", basis[w], rel[start : start + _CHUNK_PAIRS]), cos, sin
        )
        v = _in_grasp_frames(basis[w] @ -up, cos, sin)
        for k, box in enumerate(boxes):
            np.add.at(per_line[k], w, _ray_hits_box(q, v, box, reach).astype(np.int64))
    return np.all(per_line >= config.release_min_points, axis=0)


def _in_grasp_frames(dots: NDArray, cos: NDArray, sin: NDArray) -> NDArray[np.float64]:
    """(P, R, 3) grasp-frame coordinates at every roll from the five dot products (P, 5) with
    ``d, a0, e2, a0 x d, e2 x d`` (see :func:`hangs_on_both_fingers`)."""
    x = np.broadcast_to(dots[:, :1], (dots.shape[0], cos.size))
    y = dots[:, 3:4] * cos + dots[:, 4:5] * sin
    z = dots[:, 1:2] * cos + dots[:, 2:3] * sin
    return np.stack([x, y, z], axis=-1)
