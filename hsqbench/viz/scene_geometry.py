"""MuJoCo geometry as coloured triangle meshes, one merged mesh per body, in the body's frame.

A body's mesh is what MuJoCo's own viewer draws by default: the geoms of ``groups`` (MuJoCo shows
groups 0, 1 and 2; this project puts visual meshes in group 2 and collision hulls in group 3, so
the hulls are left out). Planes (the floor) are skipped: a viewer draws its own ground grid.

Each geom's vertices are moved into the body frame with the geom's pose relative to its body,
``v_body = R(geom_quat) v_geom + geom_pos`` (MuJoCo stores mesh vertices in the mesh's own,
recentred frame and folds that offset into ``geom_pos``/``geom_quat``). The colour of a geom is
its material's colour when it has a material and no own ``rgba`` (MuJoCo's rule: a geom ``rgba``
other than the default grey overrides the material); a material's RGB texture is sampled at the
vertices' texture coordinates (nearest texel), which shows the label of a YCB object.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable
from dataclasses import dataclass

import mujoco
import numpy as np
import trimesh
from numpy.typing import NDArray

#: MuJoCo's default geom colour: a geom with this rgba takes its material's colour.
_DEFAULT_RGBA = np.array([0.5, 0.5, 0.5, 1.0], dtype=np.float32)


@dataclass(frozen=True)
class BodyMesh:
    """One body's visible geometry merged into one mesh, in the body frame.

    Attributes:
        body_id: MuJoCo body id.
        body_name: MuJoCo body name (``world`` for body 0).
        vertices: (V, 3) float32, metres, body frame.
        faces: (F, 3) uint32 vertex indices, counter-clockwise seen from outside.
        colors: (V, 4) uint8 RGBA per vertex.
        normals: (V, 3) float32 unit vertex normals (:func:`vertex_normals`); a viewer draws a
            mesh without normals unlit, which hides its shape.
    """

    body_id: int
    body_name: str
    vertices: NDArray[np.float32]
    faces: NDArray[np.uint32]
    colors: NDArray[np.uint8]
    normals: NDArray[np.float32]

    @property
    def n_faces(self) -> int:
        return int(self.faces.shape[0])


@dataclass(frozen=True)
class _Part:
    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    colors: NDArray[np.uint8]


def vertex_normals(vertices: NDArray, faces: NDArray) -> NDArray[np.float64]:
    """Unit vertex normals (V, 3): the area-weighted sum of the adjacent faces' normals
    (``(b - a) x (c - a)`` is twice the area along the normal); +z for unused vertices."""
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    face_n = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    out = np.zeros_like(v)
    for k in range(3):
        np.add.at(out, f[:, k], face_n)
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(norm > 0, out / np.where(norm > 0, norm, 1.0), (0.0, 0.0, 1.0))


def _to_uint8(rgba: NDArray) -> NDArray[np.uint8]:
    return np.clip(np.round(np.asarray(rgba, dtype=np.float64) * 255.0), 0, 255).astype(np.uint8)


def _geom_rgba(model: mujoco.MjModel, g: int) -> NDArray[np.float32]:
    mat = int(model.geom_matid[g])
    rgba = np.asarray(model.geom_rgba[g], dtype=np.float32)
    if mat >= 0 and np.allclose(rgba, _DEFAULT_RGBA):
        return np.asarray(model.mat_rgba[mat], dtype=np.float32)
    return rgba


def _texture_colors(
    model: mujoco.MjModel, g: int, mesh_id: int, n_vert: int, faces: NDArray[np.int64]
) -> NDArray[np.uint8] | None:
    """Per-vertex RGB of the geom's 2-D texture (nearest texel), or None without one."""
    mat = int(model.geom_matid[g])
    if mat < 0 or model.mesh_texcoordadr[mesh_id] < 0:
        return None
    tex = int(model.mat_texid[mat, int(mujoco.mjtTextureRole.mjTEXROLE_RGB)])
    if tex < 0 or model.tex_type[tex] != mujoco.mjtTexture.mjTEXTURE_2D:
        return None
    w, h, nc = int(model.tex_width[tex]), int(model.tex_height[tex]), int(model.tex_nchannel[tex])
    if nc < 3:
        return None
    adr = int(model.tex_adr[tex])
    image = np.asarray(model.tex_data[adr : adr + w * h * nc]).reshape(h, w, nc)[..., :3]
    tc_adr, tc_num = int(model.mesh_texcoordadr[mesh_id]), int(model.mesh_texcoordnum[mesh_id])
    uv = np.asarray(model.mesh_texcoord[tc_adr : tc_adr + tc_num])
    face_adr, n_face = int(model.mesh_faceadr[mesh_id]), int(model.mesh_facenum[mesh_id])
    corner_tc = np.asarray(model.mesh_facetexcoord[face_adr : face_adr + n_face]).reshape(-1)
    # A vertex shared by faces with different texture coordinates takes one of them: nearest
    # texel colouring is a preview, not a texture.
    vert_tc = np.zeros(n_vert, dtype=np.int64)
    vert_tc[faces.reshape(-1)] = corner_tc
    u = np.clip((uv[vert_tc, 0] % 1.0) * w, 0, w - 1).astype(np.int64)
    v = np.clip((uv[vert_tc, 1] % 1.0) * h, 0, h - 1).astype(np.int64)
    return image[v, u]


def _primitive(model: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    """A triangle mesh of a primitive geom in its own frame (None for planes and unknowns)."""
    kind = int(model.geom_type[g])
    size = np.asarray(model.geom_size[g], dtype=np.float64)
    t = mujoco.mjtGeom
    if kind == t.mjGEOM_BOX:
        box = trimesh.creation.box(extents=2.0 * size)
        box.unmerge_vertices()  # a vertex per face corner: flat faces, sharp edges
        return box
    if kind == t.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    if kind == t.mjGEOM_ELLIPSOID:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        mesh.apply_scale(size)
        return mesh
    if kind == t.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2.0 * size[1], sections=24)
    if kind == t.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2.0 * size[1], radius=size[0], count=[12, 12])
    return None


def _weld(
    vertices: NDArray[np.float64], faces: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Merge vertices with identical coordinates (MuJoCo stores one per face corner) and drop
    vertices no face uses."""
    v32 = np.ascontiguousarray(vertices, dtype=np.float32)
    keys = v32.view(np.dtype((np.void, v32.dtype.itemsize * 3))).reshape(-1)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    new_faces = inverse.reshape(-1)[faces]
    used, compact = np.unique(new_faces.reshape(-1), return_inverse=True)
    return vertices[first[used]], compact.reshape(-1, 3)


def _reduce(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    colors: NDArray[np.uint8],
    max_faces: int,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.uint8]]:
    """Weld; then, for a uniformly coloured mesh, decimate to at most ``max_faces`` (quadric edge
    collapse). Textured meshes keep their faces: their per-vertex colours are the picture, and
    the object library already decimates them (16 000 faces for YCB)."""
    uniform = bool(np.all(colors == colors[0])) if len(colors) else True
    v, f = _weld(vertices, faces)
    if uniform and f.shape[0] > max_faces:
        import fast_simplification

        v, f = fast_simplification.simplify(v, f, target_count=max_faces)
        f = np.asarray(f, dtype=np.int64)
    if uniform:
        c = np.broadcast_to(colors[0], (v.shape[0], 4)).copy()
    else:  # welding merged vertices of equal position: each keeps one of their colours
        from scipy.spatial import cKDTree

        c = colors[cKDTree(vertices).query(v)[1]]
    return np.asarray(v, dtype=np.float64), f, c


#: Reduced meshes by content: a benchmark process records the same Panda in every trial.
_REDUCED: dict[tuple[bytes, int], tuple[NDArray, NDArray, NDArray]] = {}
_REDUCED_MAX_ENTRIES = 256


def _reduce_cached(
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    colors: NDArray[np.uint8],
    max_faces: int,
) -> tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.uint8]]:
    digest = hashlib.blake2b(digest_size=16)
    for arr in (vertices, faces, colors):
        digest.update(np.ascontiguousarray(arr).tobytes())
    key = (digest.digest(), int(max_faces))
    if key not in _REDUCED:
        if len(_REDUCED) >= _REDUCED_MAX_ENTRIES:
            _REDUCED.clear()
        _REDUCED[key] = _reduce(vertices, faces, colors, max_faces)
    return _REDUCED[key]


def _geom_part(model: mujoco.MjModel, g: int, max_faces: int) -> _Part | None:
    """Geom ``g`` as a coloured mesh in its body's frame, or None if it has no surface to draw."""
    rgba = _geom_rgba(model, g)
    if rgba[3] <= 0.0:
        return None
    if int(model.geom_type[g]) == mujoco.mjtGeom.mjGEOM_MESH:
        mid = int(model.geom_dataid[g])
        va, vn = int(model.mesh_vertadr[mid]), int(model.mesh_vertnum[mid])
        fa, fn = int(model.mesh_faceadr[mid]), int(model.mesh_facenum[mid])
        verts = np.asarray(model.mesh_vert[va : va + vn], dtype=np.float64)
        faces = np.asarray(model.mesh_face[fa : fa + fn], dtype=np.int64)
        tex = _texture_colors(model, g, mid, vn, faces)
        if tex is not None:
            alpha = np.full((vn, 1), _to_uint8(rgba[3]), dtype=np.uint8)
            colors = np.concatenate([tex.astype(np.uint8), alpha], axis=1)
        else:
            colors = np.broadcast_to(_to_uint8(rgba), (vn, 4)).copy()
        verts, faces, colors = _reduce_cached(verts, faces, colors, max_faces)
    else:
        mesh = _primitive(model, g)
        if mesh is None:
            return None
        verts, faces = np.asarray(mesh.vertices), np.asarray(mesh.faces, dtype=np.int64)
        colors = np.broadcast_to(_to_uint8(rgba), (verts.shape[0], 4)).copy()
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, np.asarray(model.geom_quat[g], dtype=np.float64))
    verts = verts @ rot.reshape(3, 3).T + np.asarray(model.geom_pos[g])
    return _Part(verts, faces, colors)


def body_meshes(
    model: mujoco.MjModel,
    bodies: Iterable[int] | None = None,
    groups: Iterable[int] = (0, 1, 2),
    max_faces_per_geom: int = 4000,
) -> dict[int, BodyMesh]:
    """The visible geometry of each body (of ``bodies``, default all) with any geom in ``groups``.

    Mesh geoms are welded; uniformly coloured ones are decimated to at most
    ``max_faces_per_geom`` triangles (a preview: the Menagerie Panda's 135 000 visual triangles
    would make every recording several MB larger). Textured meshes keep their triangles.

    Returns:
        body id -> :class:`BodyMesh`; bodies without a drawable geom are absent.
    """
    wanted = set(range(model.nbody) if bodies is None else (int(b) for b in bodies))
    allowed = {int(x) for x in groups}
    parts: dict[int, list[_Part]] = {}
    for g in range(model.ngeom):
        b = int(model.geom_bodyid[g])
        if b not in wanted or int(model.geom_group[g]) not in allowed:
            continue
        part = _geom_part(model, g, max_faces_per_geom)
        if part is not None:
            parts.setdefault(b, []).append(part)
    out: dict[int, BodyMesh] = {}
    for b, items in parts.items():
        offsets = np.cumsum([0] + [p.vertices.shape[0] for p in items[:-1]])
        verts = np.concatenate([p.vertices for p in items])
        faces = np.concatenate([p.faces + o for p, o in zip(items, offsets, strict=True)])
        out[b] = BodyMesh(
            body_id=b,
            body_name=model.body(b).name or "world",
            vertices=verts.astype(np.float32),
            faces=faces.astype(np.uint32),
            colors=np.concatenate([p.colors for p in items]),
            normals=vertex_normals(verts, faces).astype(np.float32),
        )
    return out
