"""Build steps 1 and 2: load and clean the mesh, then pose it (see :mod:`hsqbench.assets.build`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from hsqbench.assets.build_spec import AssetError, ObjectSpec

# --- 1. loading and cleaning -------------------------------------------------------------------


@dataclass
class _Loaded:
    visual: trimesh.Trimesh  # cleaned, with uv when textured (seams kept)
    solid: trimesh.Trimesh  # cleaned, vertices merged by position only
    uv: np.ndarray | None
    texture_file: Path | None
    texture_image: object | None  # PIL image when the texture is not a file on disk


def _clean(mesh: trimesh.Trimesh) -> trimesh.Trimesh:
    mesh.merge_vertices()
    mesh.update_faces(mesh.nondegenerate_faces())
    mesh.update_faces(mesh.unique_faces())
    mesh.remove_unreferenced_vertices()
    return mesh


def drop_fins(mesh: trimesh.Trimesh, max_rounds: int = 3) -> trimesh.Trimesh:
    """Remove dangling faces: faces with two or more edges that no other face shares.

    Scans carry a few such flaps (a triangle hinged on an edge of a closed surface: that edge then
    has three faces, the flap's other two edges one). Dropping them leaves a closed surface whose
    volume integral is exact, instead of falling back to the convex hull for the inertia.
    """
    for _ in range(max_rounds):
        edges = np.sort(mesh.edges, axis=1)
        _, inverse, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
        lonely = (counts[inverse.ravel()] == 1).reshape(-1, 3).sum(axis=1)
        if not (lonely >= 2).any():
            break
        mesh.update_faces(lonely < 2)
        mesh.remove_unreferenced_vertices()
    return mesh


def load_mesh(spec: ObjectSpec) -> _Loaded:
    """Read and clean the source mesh; errors name the file."""
    if spec.procedural is not None:
        from hsqbench.assets.procedural import make_mesh

        mesh = make_mesh(spec.procedural, spec.sections)
        solid = _clean(trimesh.Trimesh(mesh.vertices, mesh.faces, process=False))
        return _Loaded(solid.copy(), solid, None, None, None)
    path = spec.mesh_path
    assert path is not None
    if not path.is_file():
        raise AssetError(f"{spec.name}: mesh file {path} does not exist")
    try:
        loaded = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:
        raise AssetError(f"{path}: cannot read this mesh ({type(exc).__name__}: {exc})") from exc
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise AssetError(f"{path}: the file holds no triangles")
    if not np.isfinite(loaded.vertices).all():
        raise AssetError(f"{path}: the mesh has non-finite vertex coordinates")
    loaded.apply_scale(spec.scale)
    uv = texture_file = texture_image = None
    vis = loaded.visual
    textured = isinstance(vis, trimesh.visual.TextureVisuals) and vis.uv is not None
    if textured and len(vis.uv) == len(loaded.vertices):
        texture_file = next(
            (p for p in spec.input_files() if p.suffix.lower() in (".png", ".jpg", ".jpeg")), None
        )
        texture_image = getattr(vis.material, "image", None) if texture_file is None else None
    visual = _clean(loaded)
    if texture_file is not None or texture_image is not None:
        uv = np.asarray(visual.visual.uv, float)
    solid = drop_fins(_clean(trimesh.Trimesh(visual.vertices, visual.faces, process=False)))
    if len(solid.faces) < 4 or np.ptp(solid.vertices, axis=0).min() <= 0:
        raise AssetError(f"{path}: the mesh is flat or has fewer than 4 usable faces")
    return _Loaded(visual, solid, uv, texture_file, texture_image)


# --- 2. pose -------------------------------------------------------------------------------------


def upright_transform(solid: trimesh.Trimesh, up: str) -> np.ndarray:
    """4x4 rotation taking the mesh's ``up`` axis to +z (``stable``: lowest stable resting pose)."""
    if up == "z":
        return np.eye(4)
    if up == "y":  # +y -> +z, +z -> -y
        return trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0])
    if up == "x":  # +x -> +z
        return trimesh.transformations.rotation_matrix(-np.pi / 2, [0, 1, 0])
    return _lowest_stable_rotation(solid)


def _lowest_stable_rotation(solid: trimesh.Trimesh) -> np.ndarray:
    """Rotation putting the mesh on the convex-hull face plane that holds its centre of mass lowest
    among those it can rest on (the centre of mass projects inside that face). Uniform density."""
    hull = solid.convex_hull
    com = solid.center_mass if is_closed_oriented(solid) else hull.center_mass
    normals = hull.face_normals
    height = np.einsum("ij,ij->i", hull.triangles[:, 0], normals) - normals @ com
    # Project the centre of mass on each face plane and test it against that triangle; coplanar
    # triangles of one facet share a plane, so testing per triangle covers the whole facet.
    foot = (
        com
        - (normals @ com - np.einsum("ij,ij->i", hull.triangles[:, 0], normals))[:, None] * normals
    )
    bary = trimesh.triangles.points_to_barycentric(hull.triangles, foot)
    inside = (bary >= -1e-9).all(axis=1)
    if not inside.any():  # cannot happen for a closed hull; keep the file's orientation
        return np.eye(4)
    best = np.flatnonzero(inside)[np.argmin(height[inside])]
    rot = np.eye(4)
    rot[:3, :3] = trimesh.geometry.align_vectors(normals[best], [0.0, 0.0, -1.0])[:3, :3]
    return rot


def frame_transform(solid: trimesh.Trimesh, up: str) -> np.ndarray:
    """4x4 transform from file coordinates to the object frame (see ``asset.py``)."""
    rot = upright_transform(solid, up)
    points = trimesh.transform_points(solid.vertices, rot)
    lo, hi = points.min(axis=0), points.max(axis=0)
    shift = np.eye(4)
    shift[:3, 3] = [-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]]
    return shift @ rot


def is_closed_oriented(mesh: trimesh.Trimesh) -> bool:
    """Every directed edge is matched by its reverse: the surface encloses a volume."""
    edges = mesh.edges  # directed, three per face
    key_fwd = edges[:, 0].astype(np.int64) * len(mesh.vertices) + edges[:, 1]
    key_rev = edges[:, 1].astype(np.int64) * len(mesh.vertices) + edges[:, 0]
    fwd_keys, fwd_counts = np.unique(key_fwd, return_counts=True)
    rev_keys, rev_counts = np.unique(key_rev, return_counts=True)
    return bool(np.array_equal(fwd_keys, rev_keys) and np.array_equal(fwd_counts, rev_counts))
