"""Source (c): any folder of meshes (``hsqbench assets import DIR``).

Importing registers each mesh file (``.obj``, ``.stl``, ``.ply``, searched recursively) under a
name derived from its file name, as a small JSON record in ``<cache>/imported/<name>.json``
(``<cache>`` is ``hsqbench.settings.cache_dir()``). The mesh stays where it is and is read when
the object is built; the build is cached like every other object. Mass is density x volume.

Name: the file stem, lower-cased, with other characters than ``[a-z0-9_]`` replaced by ``_``;
for generic stems (``textured``, ``model``, ``mesh``, ``scan``) the parent folder's name is used.

Size: mesh files carry no unit. A mesh whose largest extent, times ``scale``, is over
:data:`MAX_EXTENT_M` or under :data:`MIN_EXTENT_M` is refused before anything is registered,
with the ``--scale`` that would make it metres (a can exported in millimetres is 90 m tall at
scale 1, and weighs tonnes).
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from pathlib import Path

from hsqbench.assets.build import UP_AXES, ObjectSpec
from hsqbench.units import check_metres

MESH_SUFFIXES = (".obj", ".stl", ".ply")
REGISTRY_DIR = "imported"
_GENERIC_STEMS = {"textured", "model", "mesh", "scan", "model_normalized"}
#: Largest extent an imported object may have, metres: the Panda's hand opens 8 cm and its
#: reach is 0.855 m, so no graspable object spans a metre; a mesh that does is in other units.
MAX_EXTENT_M = 1.0
#: Smallest largest-extent, metres: below 5 mm (the size of the sensor's 3 mm voxels) nothing is
#: seen to grasp; a mesh that small was scaled twice (metres given --scale 0.001).
MIN_EXTENT_M = 0.005


def registry_dir(cache_root: Path) -> Path:
    return cache_root / REGISTRY_DIR


def object_name(path: Path, prefix: str = "") -> str:
    stem = path.stem if path.stem.lower() not in _GENERIC_STEMS else path.parent.name
    return prefix + re.sub(r"[^a-z0-9_]", "_", stem.lower())


def find_meshes(folder: Path) -> list[Path]:
    if not folder.is_dir():
        raise FileNotFoundError(f"{folder} is not a folder of meshes")
    found = sorted(
        p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() in MESH_SUFFIXES
    )
    if not found:
        raise FileNotFoundError(f"{folder}: no mesh files ({', '.join(MESH_SUFFIXES)}) found")
    return found


def largest_extent(path: Path) -> float:
    """The largest side of a mesh file's axis-aligned bounding box, in the file's units."""
    import trimesh

    from hsqbench.assets.build import AssetError

    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:  # trimesh raises many types; name the file in ours
        raise AssetError(f"{path}: cannot read the mesh ({exc})") from None
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.vertices) == 0:
        raise AssetError(f"{path}: the file holds no mesh")
    return float(mesh.extents.max())


def check_size(path: Path, scale: float) -> None:
    """Refuse a mesh whose size at ``scale`` no graspable object has (see the module docstring).

    Raises:
        ValueError: one line naming the file, its size and the ``--scale`` to pass.
    """
    check_metres(
        path.name,
        largest_extent(path),
        scale,
        min_m=MIN_EXTENT_M,
        max_m=MAX_EXTENT_M,
        small=f"under the {MIN_EXTENT_M * 1000:g} mm the cameras can see",
        large=f"over the {MAX_EXTENT_M:g} m a graspable object can span",
    )


def register(
    folder: Path,
    cache_root: Path,
    reserved: set[str],
    density_kg_m3: float,
    scale: float = 1.0,
    up: str = "z",
    prefix: str = "",
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0),
) -> list[ObjectSpec]:
    """Register every mesh under ``folder``; returns their specs (not yet built).

    Raises ValueError when two files map to one name, or a name is taken by a YCB or procedural
    object (``reserved``); ``prefix`` resolves both. Re-importing a name replaces its record.
    """
    if up not in UP_AXES:
        raise ValueError(f"up must be one of {UP_AXES}, got {up!r}")
    meshes = find_meshes(folder)
    names = [object_name(p, prefix) for p in meshes]
    clashes = sorted({n for n in names if names.count(n) > 1})
    if clashes:
        raise ValueError(f"{folder}: several files map to the name(s) {clashes}; rename the files")
    taken = sorted(set(names) & reserved)
    if taken:
        raise ValueError(f"name(s) {taken} are taken by built-in objects; import with --prefix")
    if not scale > 0:
        raise ValueError(f"--scale must be > 0 (metres per file unit), got {scale}")
    for path in meshes:  # every file checked before any record is written
        check_size(path, scale)
    specs = [
        ObjectSpec(
            name=name,
            source="imported",
            mesh_path=path.resolve(),
            density_kg_m3=density_kg_m3,
            rgba=rgba,
            scale=scale,
            up=up,
        )
        for name, path in zip(names, meshes, strict=True)
    ]
    out = registry_dir(cache_root)
    out.mkdir(parents=True, exist_ok=True)
    for spec in specs:
        record = {
            "mesh_path": str(spec.mesh_path),
            "density_kg_m3": spec.density_kg_m3,
            "scale": spec.scale,
            "up": spec.up,
            "rgba": list(spec.rgba),
        }
        fd, tmp = tempfile.mkstemp(dir=out, suffix=".tmp")
        with os.fdopen(fd, "w") as f:
            json.dump(record, f, indent=1)
        os.replace(tmp, out / f"{spec.name}.json")
    return specs


def imported_specs(cache_root: Path) -> dict[str, ObjectSpec]:
    """All registered imports, by name."""
    folder = registry_dir(cache_root)
    specs = {}
    for record_path in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        try:
            record = json.loads(record_path.read_text())
            specs[record_path.stem] = ObjectSpec(
                name=record_path.stem,
                source="imported",
                mesh_path=Path(record["mesh_path"]),
                density_kg_m3=float(record["density_kg_m3"]),
                rgba=tuple(record["rgba"]),
                scale=float(record["scale"]),
                up=record["up"],
            )
        except (KeyError, ValueError, TypeError) as exc:
            raise ValueError(
                f"{record_path}: broken import record ({exc}); import the mesh again"
            ) from exc
    return specs
