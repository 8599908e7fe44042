"""The built object: what scenes and the simulator use (``ObjectAsset``).

Object frame (every path and number below is expressed in it): z up, the object resting upright
with its lowest point on z = 0, and x, y centred on the middle of its axis-aligned bounding box
(so the box spans [-ex/2, ex/2] x [-ey/2, ey/2] x [0, ez]). For YCB scans the canonical frame is
already upright, so only a translation is applied. The centre of mass is generally not at the
origin: use ``com``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

META_NAME = "meta.json"
SOURCES = ("ycb", "procedural", "imported")


@dataclass(frozen=True, eq=False)
class ObjectAsset:
    """A built object (see the module docstring for the frame).

    Attributes:
        name: unique object name (``mug``, ``proc_box``, ...).
        source: ``"ycb"``, ``"procedural"`` or ``"imported"``.
        mass_kg: total mass.
        com: (3,) centre of mass, metres.
        inertia: (3, 3) inertia tensor about the centre of mass, kg m^2.
        extents: (3,) bounding-box size, metres.
        visual_mesh: textured ``.obj`` (with ``vt`` coordinates when ``texture`` is set).
        texture: ``.png`` for the visual mesh, or ``None`` (then use ``rgba``).
        rgba: colour when there is no texture.
        collision_meshes: convex hulls (``.obj``), each with >= 4 non-coplanar vertices.
        build_dir: folder holding all of the above and ``meta.json``.
        info: build record (cache key, inertia method, hull count, CoACD fallback, timings).
    """

    name: str
    source: str
    mass_kg: float
    com: np.ndarray
    inertia: np.ndarray
    extents: np.ndarray
    visual_mesh: Path
    texture: Path | None
    rgba: tuple[float, float, float, float]
    collision_meshes: tuple[Path, ...]
    build_dir: Path
    info: dict[str, Any] = field(default_factory=dict)

    def to_meta(self) -> dict[str, Any]:
        """JSON-ready record; paths are stored relative to ``build_dir``."""
        return {
            "name": self.name,
            "source": self.source,
            "mass_kg": self.mass_kg,
            "com": self.com.tolist(),
            "inertia": self.inertia.tolist(),
            "extents": self.extents.tolist(),
            "visual_mesh": self.visual_mesh.name,
            "texture": None if self.texture is None else self.texture.name,
            "rgba": list(self.rgba),
            "collision_meshes": [p.name for p in self.collision_meshes],
            "info": self.info,
        }

    @classmethod
    def from_meta(cls, build_dir: Path, meta: dict[str, Any]) -> ObjectAsset:
        return cls(
            name=meta["name"],
            source=meta["source"],
            mass_kg=float(meta["mass_kg"]),
            com=np.asarray(meta["com"], float),
            inertia=np.asarray(meta["inertia"], float),
            extents=np.asarray(meta["extents"], float),
            visual_mesh=build_dir / meta["visual_mesh"],
            texture=None if meta["texture"] is None else build_dir / meta["texture"],
            rgba=tuple(float(c) for c in meta["rgba"]),
            collision_meshes=tuple(build_dir / p for p in meta["collision_meshes"]),
            build_dir=build_dir,
            info=dict(meta.get("info", {})),
        )

    @classmethod
    def load(cls, build_dir: Path) -> ObjectAsset:
        return cls.from_meta(build_dir, json.loads((build_dir / META_NAME).read_text()))
