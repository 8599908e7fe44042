"""Grasp synthesis (paper, stage two): antipodal closing lines of each hidden superquadric.

A superquadric is symmetric about its three local coordinate planes, so each principal axis meets
the surface at two antipodal points: the closing line ``lambda`` of the gripper is aligned with
each axis, and the gripper is rolled about it every ``roll_step_deg`` (10 degrees in the paper).
Shape-dependent extra lines, in the superquadric's local frame:

- ``eps1 -> 0`` (a prism): ``lambda_x`` and ``lambda_y`` slide along z, and ``lambda_z`` moves
  over a grid on the base, every ``slide_step_m`` (15 mm);
- ``eps2 -> 0`` (a rectangular cross-section): ``lambda_x`` slides along y and ``lambda_y``
  along x, every ``slide_step_m``;
- ``eps2 = 1`` and ``ax = ay`` (a circular cross-section): ``lambda`` rotates about z every
  ``rotate_step_deg`` (pi/8);
- a shape in several cases gets every combination of their motions (a cuboid's side lines
  slide over a grid on each face, a cylinder's rotated lines also slide along z).

"-> 0" and "=" are thresholds (``flat_eps_max``, ``round_eps2_tol``, ``round_axis_ratio_tol``).
Whatever the thresholds, an extra line is kept only where the surface normal at its contacts is
within ``max_tilt_deg`` of the line: the antipodal property the paper relies on, which fails
near the rounded edges of a real (eps > 0) prism.

Addition (``slide_all_shapes``): every superquadric's lines slide as a prism's and a rectangle's
do, whatever its exponents; the antipodal test above keeps the slides that still meet the surface
squarely. The paper's centre lines of a rounded body wider than the jaw depth (a bottle of
eps 0.6-1 gripped across its 6 cm thickness, 10 cm wide) put the palm into the body from every
side; the slid lines near its edge and along its height are the ones the hand can take. Each line is symmetric about its centre, so the
contacts are at ``P_G +/- h d`` with ``h`` found by bisection on the inside-outside function.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet, ClosingLines
from hsqbench.planner.hsq.stage_two.shape_rows import ShapeRows
from hsqbench.superquadric.geometry import Superquadric

#: Candidate families, as recorded in ``ClosingLines.family``.
FAMILIES = ("axis", "slide", "rotate", "rotate+slide")


def roll_angles(config: GraspConfig) -> NDArray[np.float64]:
    """Roll angles about each closing line, radians: ``0, step, ..., 360 - step`` degrees."""
    n = round(360.0 / config.roll_step_deg)
    return np.deg2rad(config.roll_step_deg * np.arange(n))


def _grid(half_extent: float, step: float) -> NDArray[np.float64]:
    """Offsets ``k * step`` strictly inside ``(-half_extent, half_extent)``, symmetric about 0."""
    n = max(int(np.ceil(half_extent / step)) - 1, 0)
    return step * np.arange(-n, n + 1)


def _axis_lines(axis: int) -> tuple[NDArray, NDArray, NDArray]:
    d = np.eye(3)[axis]
    return np.zeros((1, 3)), d, np.eye(3)[(axis + 1) % 3]


def _local_lines(
    sq: Superquadric, config: GraspConfig
) -> list[tuple[NDArray, NDArray, NDArray, int, str]]:
    """Lines of one superquadric in its frame: ``(origins (M, 3), d, e1, axis, family)`` groups."""
    a = sq.scale
    step = config.slide_step_m
    prism = sq.eps1 <= config.flat_eps_max or config.slide_all_shapes
    rectangle = sq.eps2 <= config.flat_eps_max or config.slide_all_shapes
    circle = (
        abs(sq.eps2 - 1.0) <= config.round_eps2_tol
        and abs(a[0] - a[1]) / max(a[0], a[1]) <= config.round_axis_ratio_tol
    )
    groups: list[tuple[NDArray, NDArray, NDArray, int, str]] = []
    for axis in range(3):
        origins, d, e1 = _axis_lines(axis)
        groups.append((origins, d, e1, axis, "axis"))
    # Side lines (lambda_x, lambda_y) slide along z (prism) and along the other side axis
    # (rectangle); lambda_z moves over the base (prism).
    for axis in (0, 1):
        other = 1 - axis
        slide_axes = ([2] if prism else []) + ([other] if rectangle else [])
        if not slide_axes:
            continue
        grids = np.meshgrid(*(_grid(a[k], step) for k in slide_axes), indexing="ij")
        origins = np.zeros((grids[0].size, 3))
        for k, g in zip(slide_axes, grids, strict=True):
            origins[:, k] = g.ravel()
        origins = origins[np.any(origins != 0.0, axis=1)]
        _, d, e1 = _axis_lines(axis)
        groups.append((origins, d, e1, axis, "slide"))
    if prism:
        gx, gy = np.meshgrid(_grid(a[0], step), _grid(a[1], step), indexing="ij")
        origins = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
        origins = origins[np.any(origins != 0.0, axis=1)]
        _, d, e1 = _axis_lines(2)
        groups.append((origins, d, e1, 2, "slide"))
    if circle:
        n_half = round(180.0 / config.rotate_step_deg)
        angles = np.deg2rad(config.rotate_step_deg * np.arange(n_half))
        # 0 and 90 degrees are lambda_x and lambda_y, already present.
        angles = angles[~np.isclose(np.mod(angles, 0.5 * np.pi), 0.0)]
        heights = _grid(a[2], step) if prism else np.zeros(1)
        for theta in angles:
            d = np.array([np.cos(theta), np.sin(theta), 0.0])
            for family, zs in (
                ("rotate", heights[heights == 0]),
                ("rotate+slide", heights[heights != 0]),
            ):
                if zs.size:
                    origins = np.column_stack([np.zeros((zs.size, 2)), zs])
                    groups.append((origins, d, np.array([0.0, 0.0, 1.0]), -1, family))
    return groups


def synthesize(superquadrics: Sequence[Superquadric], config: GraspConfig) -> CandidateSet:
    """Candidates of every superquadric (``source`` = its index in the sequence), all rolls.

    A superquadric thinner than ``min_part_scale_m`` (smallest semi-axis) gets no line: stage
    one's fits at its scale floor are single faces of a larger body, not parts (addition).
    """
    source_l, origins_l, dirs_l, e1_l, axes_l, families_l = [], [], [], [], [], []
    for i, sq in enumerate(superquadrics):
        if np.min(sq.scale) < config.min_part_scale_m:
            continue
        for origins, d, e1, axis, family in _local_lines(sq, config):
            n = origins.shape[0]
            source_l.append(np.full(n, i, dtype=np.int64))
            origins_l.append(origins)
            dirs_l.append(np.broadcast_to(d, (n, 3)))
            e1_l.append(np.broadcast_to(e1, (n, 3)))
            axes_l.append(np.full(n, axis, dtype=np.int64))
            families_l.append(np.full(n, FAMILIES.index(family), dtype=np.int8))
    if not source_l:
        return CandidateSet(ClosingLines.empty(), roll_angles(config))
    source, origins, dirs, e1, axis, family = (
        np.concatenate(x) for x in (source_l, origins_l, dirs_l, e1_l, axes_l, families_l)
    )
    shapes = ShapeRows.of(superquadrics, source)
    # Moved lines must start inside their superquadric (a grid node of the base may not).
    keep = (family == FAMILIES.index("axis")) | (shapes.inside_outside_pow(origins) < 1.0)
    source, origins, dirs, e1, axis, family = (
        x[keep] for x in (source, origins, dirs, e1, axis, family)
    )
    shapes = ShapeRows.of(superquadrics, source)
    half = shapes.contact_distance(origins, dirs)
    on_axis = family == FAMILIES.index("axis")
    half[on_axis] = shapes.scale[on_axis, axis[on_axis]]
    # The antipodal test for the moved lines: contact normal within max_tilt_deg of the line.
    grad = shapes.gradient(origins + half[:, None] * dirs)
    cos_tilt = np.einsum("ij,ij->i", grad, dirs) / np.linalg.norm(grad, axis=1)
    keep = on_axis | (cos_tilt >= np.cos(np.deg2rad(config.max_tilt_deg)))
    source, origins, dirs, e1, axis, family, half = (
        x[keep] for x in (source, origins, dirs, e1, axis, family, half)
    )
    rot = np.array([sq.rotation for sq in superquadrics]).reshape(-1, 3, 3)[source]
    trans = np.array([sq.translation for sq in superquadrics]).reshape(-1, 3)[source]
    lines = ClosingLines(
        centres=np.einsum("nij,nj->ni", rot, origins) + trans,
        directions=np.einsum("nij,nj->ni", rot, dirs),
        approach0=np.einsum("nij,nj->ni", rot, e1),
        half_lengths=half,
        source=source,
        axis=axis,
        family=np.array(FAMILIES, dtype="<U12")[family],
    )
    return CandidateSet(lines, roll_angles(config))
