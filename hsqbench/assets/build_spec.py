"""What a build takes (``ObjectSpec``) and where its output is cached (content-hash key).

The key hashes the mesh files' bytes, the object's parameters, the build parameters in
``AssetsConfig`` and ``BUILD_VERSION``, so an object is built once per distinct input.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from hsqbench.assets.asset import META_NAME, ObjectAsset
from hsqbench.assets.config import AssetsConfig, ProceduralObject

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
