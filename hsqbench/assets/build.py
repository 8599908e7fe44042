"""Build one object: clean, pose, decompose, weigh, write; cached by content hash.

Pipeline (``build_object``):

1. Load the mesh and clean it: merge duplicate vertices (keeping texture seams in the visual
   mesh), drop degenerate and duplicate faces and unreferenced vertices; in the solid used for
   mass properties and CoACD, also drop dangling "fin" faces (see ``drop_fins``). Scale by ``spec.scale``
   (YCB google_16k scans are already in metres).
2. Pose: rotate the ``spec.up`` axis to +z (YCB: already z up, no rotation), then translate so the
   lowest point is on z = 0 and the bounding-box centre is on x = y = 0 (see ``asset.py``).
3. Mass properties of the solid (divergence theorem over the triangles): used as is when the
   surface is closed and consistently oriented (every directed edge has its reverse; non-manifold
   edges are allowed), else from its convex hull, with a warning and ``info["inertia_method"]``.
   The tensor at unit density is scaled to the object's mass (YCB table, or density x volume).
4. Convex decomposition with CoACD on a copy decimated to ``coacd.pre_simplify_faces``; hulls too
   small for MuJoCo are merged into their nearest neighbour. A CoACD failure (or no usable hull)
   falls back to the convex hull of the whole mesh, with a warning.
5. Write ``visual.obj`` (+ ``texture.png``), ``hull_NN.obj``, ``meta.json`` into a temporary
   folder, check that MuJoCo compiles the object, then rename the folder to
   ``<cache>/<name>-<key>``: a killed build never leaves a half-written entry.

The key hashes the mesh files' bytes, the object's parameters, the build parameters in
``AssetsConfig`` and ``BUILD_VERSION``, so an object is built once per distinct input.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import trimesh

from hsqbench.assets.asset import META_NAME, ObjectAsset
from hsqbench.assets.config import AssetsConfig, CoacdConfig, HullConfig, ProceduralObject

# Bump when the build code changes its output, so old cache entries are not reused.
BUILD_VERSION = 2
UP_AXES = ("z", "y", "x", "stable")


class AssetError(RuntimeError):
    """An object cannot be built (unreadable or broken mesh, bad parameters)."""


class AssetWarning(UserWarning):
    """A build went on with a fallback (convex hull for inertia or collision)."""


@dataclass(frozen=True)
class ObjectSpec:
    """Everything needed to build one object.

    Attributes:
        name, source: as in ``ObjectAsset``.
        mesh_path: the mesh file (obj/stl/ply/...), ``None`` for procedural objects.
        mass_kg: the object's mass, or ``None`` to use ``density_kg_m3`` x volume.
        density_kg_m3: used when ``mass_kg`` is ``None``.
        rgba: colour when there is no texture.
        scale: multiplies the file's coordinates to get metres.
        up: which axis of the file points up: ``z`` (as is), ``y``, ``x``, or ``stable`` (rest
            on the convex-hull face that puts the centre of mass lowest, among faces it can
            stand on).
        procedural: the generator entry for procedural objects.
        sections: facet count of curved procedural shapes.
    """

    name: str
    source: str
    mesh_path: Path | None = None
    mass_kg: float | None = None
    density_kg_m3: float | None = None
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)
    scale: float = 1.0
    up: str = "z"
    procedural: ProceduralObject | None = None
    sections: int = 48

    def __post_init__(self) -> None:
        if self.up not in UP_AXES:
            raise ValueError(f"{self.name}: up must be one of {UP_AXES}, got {self.up!r}")
        if not (self.scale > 0 and np.isfinite(self.scale)):
            raise ValueError(f"{self.name}: scale must be a positive number, got {self.scale}")
        if self.mass_kg is None and not (self.density_kg_m3 and self.density_kg_m3 > 0):
            raise ValueError(f"{self.name}: give a positive mass_kg or density_kg_m3")
        if self.mass_kg is not None and not self.mass_kg > 0:
            raise ValueError(f"{self.name}: mass_kg must be > 0, got {self.mass_kg}")
        if (self.mesh_path is None) == (self.procedural is None):
            raise ValueError(f"{self.name}: give exactly one of mesh_path and procedural")

    def input_files(self) -> list[Path]:
        """The mesh file and, for OBJ, its material libraries and their texture images."""
        if self.mesh_path is None:
            return []
        files = [self.mesh_path]
        if self.mesh_path.suffix.lower() == ".obj" and self.mesh_path.is_file():
            for mtl in _obj_mtllibs(self.mesh_path):
                files.append(mtl)
                files.extend(_mtl_textures(mtl))
        return files


def _obj_mtllibs(path: Path) -> list[Path]:
    out = []
    with path.open(errors="replace") as f:
        for line in f:
            if line.startswith("mtllib"):
                target = path.parent / line.split(maxsplit=1)[1].strip()
                if target.is_file():
                    out.append(target)
    return out


def _mtl_textures(mtl: Path) -> list[Path]:
    out = []
    for line in mtl.read_text(errors="replace").splitlines():
        parts = line.split()
        if parts and parts[0] == "map_Kd" and len(parts) > 1:
            target = mtl.parent / parts[-1]
            if target.is_file() and target not in out:
                out.append(target)
    return out


def build_parameters(spec: ObjectSpec, config: AssetsConfig) -> dict:
    """The parameters that determine a build's output (hashed into the cache key)."""
    spec_dict = asdict(spec)
    spec_dict["mesh_path"] = None if spec.mesh_path is None else spec.mesh_path.name
    return {
        "build_version": BUILD_VERSION,
        "spec": spec_dict,
        "coacd": asdict(config.coacd),
        "hulls": asdict(config.hulls),
        "visual": asdict(config.visual),
    }


def cache_key(spec: ObjectSpec, config: AssetsConfig) -> str:
    """sha256 (first 16 hex digits) of the input files' bytes and the build parameters."""
    digest = hashlib.sha256(json.dumps(build_parameters(spec, config), sort_keys=True).encode())
    for path in spec.input_files():
        if not path.is_file():
            raise AssetError(f"{spec.name}: mesh file {path} does not exist")
        digest.update(path.name.encode())
        with path.open("rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    return digest.hexdigest()[:16]


def entry_dir(spec: ObjectSpec, config: AssetsConfig, cache_root: Path) -> Path:
    return cache_root / f"{spec.name}-{cache_key(spec, config)}"


def load_cached(spec: ObjectSpec, config: AssetsConfig, cache_root: Path) -> ObjectAsset | None:
    folder = entry_dir(spec, config, cache_root)
    return ObjectAsset.load(folder) if (folder / META_NAME).is_file() else None


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


# --- 3. mass properties --------------------------------------------------------------------------


def is_closed_oriented(mesh: trimesh.Trimesh) -> bool:
    """Every directed edge is matched by its reverse: the surface encloses a volume."""
    edges = mesh.edges  # directed, three per face
    key_fwd = edges[:, 0].astype(np.int64) * len(mesh.vertices) + edges[:, 1]
    key_rev = edges[:, 1].astype(np.int64) * len(mesh.vertices) + edges[:, 0]
    fwd_keys, fwd_counts = np.unique(key_fwd, return_counts=True)
    rev_keys, rev_counts = np.unique(key_rev, return_counts=True)
    return bool(np.array_equal(fwd_keys, rev_keys) and np.array_equal(fwd_counts, rev_counts))


@dataclass(frozen=True)
class MassProperties:
    mass_kg: float
    volume_m3: float
    com: np.ndarray  # (3,) metres
    inertia: np.ndarray  # (3, 3) about the COM, kg m^2
    method: str  # "mesh" or "convex_hull"


def mass_properties(
    solid: trimesh.Trimesh, mass_kg: float | None, density_kg_m3: float | None, label: str
) -> MassProperties:
    """Uniform-density mass properties: ``I = (m / V) * integral of (r.r Id - r r^T) dV``."""
    method = "mesh"
    body = solid
    if not (is_closed_oriented(solid) and solid.volume > 0):
        warnings.warn(
            f"{label}: the mesh is not a closed surface; mass and inertia use its convex hull",
            AssetWarning,
            stacklevel=2,
        )
        body, method = solid.convex_hull, "convex_hull"
    props = trimesh.triangles.mass_properties(body.triangles, density=1.0)
    volume = float(props.volume)
    if not volume > 0:
        raise AssetError(f"{label}: the mesh encloses no volume")
    mass = float(mass_kg) if mass_kg is not None else float(density_kg_m3) * volume
    inertia = np.asarray(props.inertia, float) * (mass / volume)
    inertia = 0.5 * (inertia + inertia.T)
    eig = np.linalg.eigvalsh(inertia)
    if not (
        np.isfinite(inertia).all() and eig.min() > 0 and 2 * eig.max() <= eig.sum() * (1 + 1e-6)
    ):
        raise AssetError(f"{label}: the mesh gives an invalid inertia tensor (eigenvalues {eig})")
    return MassProperties(mass, volume, np.asarray(props.center_mass, float), inertia, method)


# --- 4. convex decomposition ---------------------------------------------------------------------


def _hull(points: np.ndarray) -> trimesh.Trimesh | None:
    """Convex hull of ``points``, or ``None`` when they are (nearly) coplanar."""
    if len(points) < 4:
        return None
    try:
        hull = trimesh.convex.convex_hull(points)
    except Exception:  # qhull rejects coplanar or degenerate input
        return None
    return hull if hull.volume > 0 and len(hull.vertices) >= 4 else None


def clean_hulls(parts: list[np.ndarray], config: HullConfig) -> list[trimesh.Trimesh]:
    """Make each part a proper convex hull and merge too-small ones into their nearest neighbour.

    ``parts`` are vertex arrays. A hull is too small when its volume is below
    ``config.min_volume_fraction`` of the total or below ``config.min_volume_m3``; it is merged
    (hull of the union of vertices) into the hull with the nearest centroid. Degenerate parts with
    no neighbour to merge into are dropped, so the result may be empty (the caller falls back).
    """
    points = [np.asarray(p, float) for p in parts if len(p)]
    hulls = [_hull(p) for p in points]
    while True:
        vols = np.array([h.volume if h is not None else 0.0 for h in hulls])
        if len(hulls) == 0:
            return []
        floor = max(config.min_volume_fraction * vols.sum(), config.min_volume_m3)
        small = np.flatnonzero(vols < floor)
        if len(small) == 0:
            return [h for h in hulls if h is not None]
        i = int(small[np.argmin(vols[small])])
        if len(hulls) == 1:
            return []
        centroids = np.array([p.mean(axis=0) for p in points])
        dist = np.linalg.norm(centroids - centroids[i], axis=1)
        dist[i] = np.inf
        j = int(np.argmin(dist))
        points[j] = np.concatenate([points[j], points[i]])
        hulls[j] = _hull(points[j])
        del points[i], hulls[i]


def decompose(
    solid: trimesh.Trimesh, coacd_cfg: CoacdConfig, hull_cfg: HullConfig, label: str
) -> tuple[list[trimesh.Trimesh], dict]:
    """CoACD hulls of ``solid`` (object frame), with the fallback to its convex hull."""
    import coacd

    info: dict = {"coacd_input_faces": len(solid.faces)}
    mesh = solid
    if coacd_cfg.pre_simplify_faces and len(solid.faces) > coacd_cfg.pre_simplify_faces:
        try:
            mesh = solid.simplify_quadric_decimation(face_count=coacd_cfg.pre_simplify_faces)
            info["coacd_input_faces"] = len(mesh.faces)
        except Exception as exc:  # decimation is an optimisation: go on with the full mesh
            warnings.warn(
                f"{label}: decimation failed ({exc}); CoACD gets the full mesh",
                AssetWarning,
                stacklevel=2,
            )
    params = {k: v for k, v in asdict(coacd_cfg).items() if k != "pre_simplify_faces"}
    start, start_cpu = time.perf_counter(), time.process_time()
    hulls: list[trimesh.Trimesh] = []
    try:
        coacd.set_log_level("error")
        parts = coacd.run_coacd(coacd.Mesh(mesh.vertices, mesh.faces), **params)
        hulls = clean_hulls([np.asarray(v) for v, _ in parts], hull_cfg)
        info["coacd_raw_hulls"] = len(parts)
        if not hulls:
            raise AssetError("CoACD returned no hull MuJoCo can use")
        info["collision_method"] = "coacd"
    except Exception as exc:
        warnings.warn(
            f"{label}: CoACD failed ({type(exc).__name__}: {exc}); collision uses the convex hull",
            AssetWarning,
            stacklevel=2,
        )
        hulls = [solid.convex_hull]
        info["collision_method"] = "convex_hull"
        info["coacd_error"] = f"{type(exc).__name__}: {exc}"
    # Wall time, and CPU time of this process (what the build costs when cores are shared).
    info["coacd_s"] = round(time.perf_counter() - start, 3)
    info["coacd_cpu_s"] = round(time.process_time() - start_cpu, 3)
    return hulls, info


# --- 5. writing ----------------------------------------------------------------------------------


def write_obj(
    path: Path, vertices: np.ndarray, faces: np.ndarray, uv: np.ndarray | None = None
) -> None:
    """A plain OBJ: ``v`` lines, optional ``vt`` lines, 1-based ``f`` lines (``v/vt`` with uv)."""
    lines = ["# hsqbench object asset"]
    lines += [f"v {x:.8g} {y:.8g} {z:.8g}" for x, y, z in vertices]
    f1 = np.asarray(faces, int) + 1
    if uv is not None:
        lines += [f"vt {u:.8g} {v:.8g}" for u, v in uv]
        lines += [f"f {a}/{a} {b}/{b} {c}/{c}" for a, b, c in f1]
    else:
        lines += [f"f {a} {b} {c}" for a, b, c in f1]
    path.write_text("\n".join(lines) + "\n")


def _visual_mesh(
    loaded: _Loaded, max_faces: int, label: str
) -> tuple[trimesh.Trimesh, np.ndarray | None]:
    visual, uv = loaded.visual, loaded.uv
    if len(visual.faces) <= max_faces:
        return visual, uv
    if uv is not None:
        warnings.warn(
            f"{label}: textured visual mesh has {len(visual.faces)} faces (> {max_faces}); kept as is "
            "because decimation would break its texture coordinates",
            AssetWarning,
            stacklevel=2,
        )
        return visual, uv
    return loaded.solid.simplify_quadric_decimation(face_count=max_faces), None


def build_object(spec: ObjectSpec, config: AssetsConfig, cache_root: Path) -> ObjectAsset:
    """Build ``spec`` into ``cache_root`` (or return the cached entry)."""
    final = entry_dir(spec, config, cache_root)
    if (final / META_NAME).is_file():
        return ObjectAsset.load(final)
    start, start_cpu = time.perf_counter(), time.process_time()
    label = f"{spec.name} ({spec.mesh_path or 'procedural'})"
    loaded = load_mesh(spec)
    transform = frame_transform(loaded.solid, spec.up)
    loaded.visual.apply_transform(transform)
    loaded.solid.apply_transform(transform)
    props = mass_properties(loaded.solid, spec.mass_kg, spec.density_kg_m3, label)
    hulls, info = decompose(loaded.solid, config.coacd, config.hulls, label)
    visual, uv = _visual_mesh(loaded, config.visual.max_faces, label)

    cache_root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".tmp-{spec.name}-", dir=cache_root))
    try:
        write_obj(tmp / "visual.obj", visual.vertices, visual.faces, uv)
        texture = None
        if uv is not None and loaded.texture_file is not None:
            texture = tmp / "texture.png"
            if loaded.texture_file.suffix.lower() == ".png":
                shutil.copyfile(loaded.texture_file, texture)
            else:
                _save_png(loaded.texture_file, texture)
        elif uv is not None and loaded.texture_image is not None:
            texture = tmp / "texture.png"
            loaded.texture_image.save(texture)  # type: ignore[attr-defined]
        hull_paths = []
        for k, hull in enumerate(hulls):
            hull_paths.append(tmp / f"hull_{k:02d}.obj")
            write_obj(hull_paths[-1], hull.vertices, hull.faces)
        info.update(
            cache_key=final.name.rsplit("-", 1)[1],
            inertia_method=props.method,
            volume_m3=props.volume_m3,
            n_hulls=len(hulls),
            visual_faces=len(visual.faces),
            source_file=None if spec.mesh_path is None else str(spec.mesh_path),
            frame_transform=transform.tolist(),
            build_s=round(time.perf_counter() - start, 3),
            build_cpu_s=round(time.process_time() - start_cpu, 3),
            parameters=build_parameters(spec, config),
        )
        asset = ObjectAsset(
            name=spec.name,
            source=spec.source,
            mass_kg=props.mass_kg,
            com=props.com,
            inertia=props.inertia,
            extents=np.ptp(loaded.solid.vertices, axis=0),
            visual_mesh=tmp / "visual.obj",
            texture=texture,
            rgba=tuple(float(c) for c in spec.rgba),
            collision_meshes=tuple(hull_paths),
            build_dir=tmp,
            info=info,
        )
        _check_compiles(asset, label)
        (tmp / META_NAME).write_text(json.dumps(asset.to_meta(), indent=1))
        try:
            os.rename(tmp, final)
        except OSError:
            if not (final / META_NAME).is_file():  # not a concurrent build of the same entry
                raise
            shutil.rmtree(tmp, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return ObjectAsset.load(final)


def _save_png(source: Path, target: Path) -> None:
    from PIL import Image

    with Image.open(source) as image:
        image.save(target)


def _check_compiles(asset: ObjectAsset, label: str) -> None:
    import mujoco

    from hsqbench.assets.mjcf import object_mjcf

    try:
        mujoco.MjModel.from_xml_string(object_mjcf(asset))
    except Exception as exc:
        raise AssetError(f"{label}: MuJoCo rejects the built asset: {exc}") from exc
