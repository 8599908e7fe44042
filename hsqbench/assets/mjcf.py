"""Minimal MJCF for one built object: the object on a free joint above a ground plane.

Used to check that every built object compiles, and as a reference for how the fields of
``ObjectAsset`` map to MJCF: the visual mesh (textured when ``texture`` is set) is a
non-colliding geom in group 2; each convex hull is a colliding mesh geom in group 3; the
inertial comes from the asset (``com``, ``mass_kg``, ``inertia``), never from the geoms.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from hsqbench.assets.asset import ObjectAsset


def _vec(values: np.ndarray) -> str:
    return " ".join(f"{v:.9g}" for v in np.ravel(values))


def asset_xml(asset: ObjectAsset, prefix: str = "") -> str:
    """``<asset>`` children (meshes, texture, material) named ``{prefix}{asset.name}_*``."""
    n = f"{prefix}{asset.name}"
    lines = []
    if asset.texture is not None:
        lines.append(f'<texture name="{n}_tex" type="2d" file={quoteattr(str(asset.texture))}/>')
        lines.append(f'<material name="{n}_mat" texture="{n}_tex"/>')
    else:
        lines.append(f'<material name="{n}_mat" rgba="{_vec(np.asarray(asset.rgba))}"/>')
    # The visual mesh of a scan need not be closed: "shell" inertia keeps MuJoCo from rejecting
    # it (the body's inertial is given explicitly anyway).
    lines.append(
        f'<mesh name="{n}_visual" file={quoteattr(str(asset.visual_mesh))} inertia="shell"/>'
    )
    for k, path in enumerate(asset.collision_meshes):
        lines.append(f'<mesh name="{n}_hull_{k:02d}" file={quoteattr(str(path))}/>')
    return "\n".join(lines)


def body_xml(
    asset: ObjectAsset, pos: tuple[float, float, float] = (0.0, 0.0, 0.0), prefix: str = ""
) -> str:
    """A ``<body>`` with a free joint, the explicit inertial, the visual geom and the hull geoms."""
    n = f"{prefix}{asset.name}"
    i = asset.inertia
    full = np.array([i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]])
    lines = [
        f'<body name="{n}" pos="{_vec(np.asarray(pos))}">',
        f'  <freejoint name="{n}_joint"/>',
        f'  <inertial pos="{_vec(asset.com)}" mass="{asset.mass_kg:.9g}" fullinertia="{_vec(full)}"/>',
        f'  <geom name="{n}_visual" type="mesh" mesh="{n}_visual" material="{n}_mat" '
        'contype="0" conaffinity="0" group="2"/>',
    ]
    for k in range(len(asset.collision_meshes)):
        lines.append(
            f'  <geom name="{n}_hull_{k:02d}" type="mesh" mesh="{n}_hull_{k:02d}" group="3" '
            f'rgba="{_vec(np.asarray(asset.rgba))}"/>'
        )
    lines.append("</body>")
    return "\n".join(lines)


def object_mjcf(asset: ObjectAsset, drop_height_m: float = 0.05) -> str:
    """A standalone model: ground plane and the object ``drop_height_m`` above it."""
    return "\n".join(
        [
            f'<mujoco model="object_{asset.name}">',
            "<asset>",
            asset_xml(asset),
            "</asset>",
            "<worldbody>",
            '<light pos="0 0 1.5" dir="0 0 -1"/>',
            '<geom name="floor" type="plane" size="1 1 0.05"/>',
            body_xml(asset, pos=(0.0, 0.0, drop_height_m)),
            "</worldbody>",
            "</mujoco>",
        ]
    )
