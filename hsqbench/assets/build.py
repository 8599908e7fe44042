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

The steps live in :mod:`~hsqbench.assets.build_spec` (spec and cache key),
:mod:`~hsqbench.assets.mesh_prep` (1 and 2), :mod:`~hsqbench.assets.mass` (3) and
:mod:`~hsqbench.assets.decompose` (4); their public names stay importable from here.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
import trimesh

from hsqbench.assets.asset import META_NAME, ObjectAsset
from hsqbench.assets.build_spec import (
    BUILD_VERSION,
    UP_AXES,
    AssetError,
    AssetWarning,
    ObjectSpec,
    build_parameters,
    cache_key,
    entry_dir,
    load_cached,
)
from hsqbench.assets.config import AssetsConfig
from hsqbench.assets.decompose import clean_hulls, decompose
from hsqbench.assets.mass import MassProperties, mass_properties
from hsqbench.assets.mesh_prep import (
    _Loaded,
    drop_fins,
    frame_transform,
    is_closed_oriented,
    load_mesh,
    upright_transform,
)

__all__ = [
    "BUILD_VERSION",
    "UP_AXES",
    "AssetError",
    "AssetWarning",
    "MassProperties",
    "ObjectSpec",
    "build_object",
    "build_parameters",
    "cache_key",
    "clean_hulls",
    "decompose",
    "drop_fins",
    "entry_dir",
    "frame_transform",
    "is_closed_oriented",
    "load_cached",
    "load_mesh",
    "mass_properties",
    "upright_transform",
    "write_obj",
]


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
        texture = _write_texture(loaded, uv, tmp)
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
        _publish(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return ObjectAsset.load(final)


def _write_texture(loaded: _Loaded, uv: np.ndarray | None, folder: Path) -> Path | None:
    """The mesh's texture as ``folder/texture.png`` (PNG copied, other formats converted), or
    None when the visual mesh has no UVs or the source no texture."""
    if uv is None:
        return None
    texture = folder / "texture.png"
    if loaded.texture_file is not None:
        if loaded.texture_file.suffix.lower() == ".png":
            shutil.copyfile(loaded.texture_file, texture)
        else:
            _save_png(loaded.texture_file, texture)
        return texture
    if loaded.texture_image is not None:
        loaded.texture_image.save(texture)  # type: ignore[attr-defined]
        return texture
    return None


def _publish(tmp: Path, final: Path) -> None:
    """Move a finished build into place in one rename; if a concurrent build of the same entry
    got there first, its entry stands and this one is dropped."""
    try:
        os.rename(tmp, final)
    except OSError:
        if not (final / META_NAME).is_file():
            raise
        shutil.rmtree(tmp, ignore_errors=True)


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
