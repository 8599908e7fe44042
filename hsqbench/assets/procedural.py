"""Source (d): built-in procedural objects made with trimesh, for tests and for running with
nothing downloaded.

Each generator returns a closed, consistently wound triangle mesh in metres with z up; the build
step puts it in the object frame (base on z = 0, x/y centred) like any other source. Shapes and
sizes come from ``configs/assets.yaml`` (``procedural.objects``).

- box: a cuboid of size (x, y, z).
- cylinder: radius r, height h, axis along z.
- sphere: radius r (an icosphere with about ``sections`` segments around the equator).
- l: an L-shaped prism lying flat: arms of length (ax along x, ay along y), arm width w, height h.
- mug: a cup of outer radius R, height H and wall t (revolved profile, closed bottom of thickness
  t) with a C-shaped handle: a rectangular tube (radial thickness t, width w along y) following a
  half circle of radius rh in the x-z plane, whose ends rest on the outer wall. The handle is a
  second closed component touching the cup (it overlaps the wall by at most the sagitta of the
  handle width, under 0.5 mm), so volume and inertia are sums of the two parts.
"""

from __future__ import annotations

import numpy as np
import trimesh

from hsqbench.assets.config import ProceduralConfig, ProceduralObject

_N_SIZES = {"box": 3, "cylinder": 2, "sphere": 1, "l": 4, "mug": 5}


def procedural_names(config: ProceduralConfig) -> list[str]:
    return [obj.name for obj in config.objects]


def find_procedural(name: str, config: ProceduralConfig) -> ProceduralObject | None:
    return next((obj for obj in config.objects if obj.name == name), None)


def make_mesh(obj: ProceduralObject, sections: int) -> trimesh.Trimesh:
    """The mesh of one procedural object (metres, z up, not yet posed)."""
    if obj.kind not in _N_SIZES:
        raise ValueError(
            f"{obj.name}: unknown procedural kind {obj.kind!r}; known: {sorted(_N_SIZES)}"
        )
    if len(obj.size_m) != _N_SIZES[obj.kind]:
        raise ValueError(
            f"{obj.name}: kind {obj.kind!r} takes {_N_SIZES[obj.kind]} sizes, got {len(obj.size_m)}"
        )
    if min(obj.size_m) <= 0.0:
        raise ValueError(f"{obj.name}: sizes must be > 0, got {obj.size_m}")
    s = obj.size_m
    if obj.kind == "box":
        return trimesh.creation.box(extents=s)
    if obj.kind == "cylinder":
        return trimesh.creation.cylinder(radius=s[0], height=s[1], sections=sections)
    if obj.kind == "sphere":
        # Subdivision level 3 has 48 edges around the equator of the unit icosahedron's refinement.
        level = max(1, int(np.ceil(np.log2(max(sections, 6) / 6.0))))
        return trimesh.creation.icosphere(subdivisions=level, radius=s[0])
    if obj.kind == "l":
        return _l_prism(*s)
    return _mug(*s, sections=sections)


def _l_prism(ax: float, ay: float, width: float, height: float) -> trimesh.Trimesh:
    if width >= min(ax, ay):
        raise ValueError(f"L: arm width {width} must be smaller than both arm lengths {ax}, {ay}")
    outline = np.array([[0, 0], [ax, 0], [ax, width], [width, width], [width, ay], [0, ay]], float)
    # The L is star-shaped from its corner vertex 0, so a fan from it triangulates it.
    fan = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
    return trimesh.creation.extrude_triangulation(outline, fan, height)


def _mug(
    radius: float,
    height: float,
    wall: float,
    handle_radius: float,
    handle_width: float,
    sections: int,
) -> trimesh.Trimesh:
    if 2 * wall >= radius or wall >= height or 2 * handle_radius + wall >= height:
        raise ValueError(
            f"mug: wall {wall} and handle radius {handle_radius} do not fit a cup of "
            f"radius {radius} and height {height}"
        )
    # Closed (r, z) profile of the cup wall and bottom, revolved about z.
    profile = np.array(
        [
            [0, 0],
            [radius, 0],
            [radius, height],
            [radius - wall, height],
            [radius - wall, wall],
            [0, wall],
        ],
        float,
    )
    cup = trimesh.creation.revolve(profile, sections=sections)
    if cup.volume < 0:
        cup.invert()
    handle = _handle_tube(radius, height / 2.0, handle_radius, wall, handle_width, sections)
    mesh = trimesh.util.concatenate([cup, handle])
    mesh.merge_vertices()
    return mesh


def _handle_tube(
    x0: float, zc: float, arc_radius: float, thickness: float, width: float, sections: int
) -> trimesh.Trimesh:
    """A rectangular tube along the half circle ``(x0 + rh cos a, 0, zc + rh sin a)``,
    a in [-pi/2, pi/2], with capped ends on the plane x = x0."""
    n = max(sections // 2, 8) + 1
    a = np.linspace(-np.pi / 2, np.pi / 2, n)
    radial = np.stack([np.cos(a), np.zeros(n), np.sin(a)], axis=1)
    centre = np.array([x0, 0.0, zc]) + arc_radius * radial
    y = np.array([0.0, 1.0, 0.0])
    # Cross-section corners (radial offset, y offset), counter-clockwise seen along the path.
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float) * [thickness / 2, width / 2]
    verts = (
        centre[:, None, :]
        + corners[None, :, 0, None] * radial[:, None, :]
        + corners[None, :, 1, None] * y[None, None, :]
    ).reshape(-1, 3)
    i = np.arange(n - 1)[:, None]
    k = np.arange(4)[None, :]
    a0, a1 = i * 4 + k, i * 4 + (k + 1) % 4
    b0, b1 = a0 + 4, a1 + 4
    sides = np.concatenate(
        [np.stack([a0, b0, b1], -1).reshape(-1, 3), np.stack([a0, b1, a1], -1).reshape(-1, 3)]
    )
    last = 4 * (n - 1)
    caps = np.array([[0, 1, 2], [0, 2, 3], [last, last + 1, last + 2], [last, last + 2, last + 3]])
    # Outward direction of each face: away from the path for the sides, along -/+ tangent for caps.
    seg_centre = 0.5 * (centre[:-1] + centre[1:])
    faces = np.concatenate([sides, caps])
    centroid = verts[faces].mean(axis=1)
    seg = np.concatenate([np.tile(np.arange(n - 1).repeat(4), 2), [0, 0, n - 2, n - 2]])
    outward = centroid - seg_centre[seg]
    tangent = centre[1:] - centre[:-1]
    outward[-4:-2] = -tangent[0]
    outward[-2:] = tangent[-1]
    normal = np.cross(
        verts[faces[:, 1]] - verts[faces[:, 0]], verts[faces[:, 2]] - verts[faces[:, 0]]
    )
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    faces[flip] = faces[flip][:, ::-1]
    tube = trimesh.Trimesh(verts, faces, process=True)
    return tube
