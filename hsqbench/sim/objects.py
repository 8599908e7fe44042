"""Objects as MuJoCo bodies: a free body with convex collision hulls, a textured visual mesh and
the asset's own mass and inertia.

Objects come from the object library (:func:`hsqbench.assets.library.get_object`), or are any
value with the same fields (:class:`ObjectLike`), so tests can build their own. The object frame
has z up, the base on z = 0 and x/y centred; the body frame is the object frame.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import mujoco
import numpy as np

from hsqbench.sim.physics import ContactConfig

VISUAL_GROUP = 2  # MuJoCo convention: group 2 visual geoms, group 3 collision geoms
COLLISION_GROUP = 3


class ObjectLike(Protocol):
    """The fields of :class:`hsqbench.assets.library.ObjectAsset` that the simulator reads.

    Lengths in metres and kilograms, in the object frame. ``inertia`` is the 3x3 inertia tensor
    about the centre of mass (kg m^2); ``extents`` the axis-aligned size (x, y, z).
    """

    name: str
    mass_kg: float
    com: np.ndarray
    inertia: np.ndarray
    extents: np.ndarray
    visual_mesh: Path
    texture: Path | None
    rgba: tuple[float, float, float, float]
    collision_meshes: tuple[Path, ...]


def resolve_object(item: str | ObjectLike) -> ObjectLike:
    """An object by library name (built on first use), or the object itself."""
    if isinstance(item, str):
        from hsqbench.assets.library import get_object

        return get_object(item)
    return item


def principal_inertia(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (3,) and the quaternion (w, x, y, z) of the principal axes.

    Eigen-decomposition ``I = R diag(m) R^T`` with ``R`` a proper rotation (det +1).

    Raises:
        ValueError: for a non-symmetric, non-finite or non-positive-definite tensor.
    """
    inertia = np.asarray(inertia, dtype=float)
    if inertia.shape != (3, 3) or not np.all(np.isfinite(inertia)):
        raise ValueError(f"inertia must be a finite 3x3 matrix, got {inertia!r}")
    if not np.allclose(inertia, inertia.T, rtol=1e-6, atol=1e-12):
        raise ValueError("inertia must be symmetric")
    moments, axes = np.linalg.eigh(inertia)
    if moments[0] <= 0:
        raise ValueError(f"inertia must be positive definite, eigenvalues {moments}")
    if np.linalg.det(axes) < 0:
        axes[:, 2] *= -1.0
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, axes.reshape(-1))
    return moments, quat


def add_object_body(
    parent: mujoco.MjsBody,
    spec: mujoco.MjSpec,
    obj: ObjectLike,
    body_name: str,
    pos: np.ndarray,
    quat: np.ndarray,
    contact: ContactConfig,
    mass_scale: float = 1.0,
    size_scale: float = 1.0,
) -> mujoco.MjsBody:
    """Add ``obj`` as a free body named ``body_name`` at (pos, quat) under ``parent``.

    Collision geoms are the convex hulls (``contype = conaffinity = 1``, group 3) with the
    ``contact`` parameters; the visual mesh is a non-colliding group-2 geom with the texture
    when there is one. Asset names are prefixed with ``body_name`` so objects never clash.
    ``mass_scale`` multiplies the mass and the inertia (the same shape, denser or lighter).
    ``size_scale`` scales the object about its frame's origin (the base centre): meshes and
    centre of mass by ``s``, mass by ``s^3`` (the same density) and inertia by ``s^5``.
    """
    if not size_scale > 0:
        raise ValueError(f"{obj.name}: size_scale must be positive, got {size_scale}")
    if obj.mass_kg <= 0 or not np.isfinite(obj.mass_kg):
        raise ValueError(f"{obj.name}: mass must be positive, got {obj.mass_kg}")
    if not obj.collision_meshes:
        raise ValueError(f"{obj.name}: no collision meshes")
    moments, iquat = principal_inertia(obj.inertia)
    body = parent.add_body(name=body_name, pos=list(map(float, pos)), quat=list(map(float, quat)))
    body.add_freejoint(name=f"{body_name}/free")
    body.explicitinertial = True
    # A mass scale keeps the density distribution: the inertia scales with the mass.
    s = float(size_scale)
    body.mass = float(obj.mass_kg) * mass_scale * s**3
    body.ipos = list(map(float, np.asarray(obj.com) * s))
    body.inertia = list(map(float, moments * mass_scale * s**5))
    body.iquat = list(map(float, iquat))
    for i, path in enumerate(obj.collision_meshes):
        mesh_name = f"{body_name}/hull{i}"
        spec.add_mesh(name=mesh_name, file=str(path), scale=[s, s, s])
        geom = body.add_geom(
            name=mesh_name,
            type=mujoco.mjtGeom.mjGEOM_MESH,
            meshname=mesh_name,
            group=COLLISION_GROUP,
            rgba=list(obj.rgba),
        )
        contact.apply(geom)
    visual = f"{body_name}/visual"
    spec.add_mesh(name=visual, file=str(obj.visual_mesh), scale=[s, s, s])
    vis = body.add_geom(
        name=visual,
        type=mujoco.mjtGeom.mjGEOM_MESH,
        meshname=visual,
        contype=0,
        conaffinity=0,
        group=VISUAL_GROUP,
        rgba=list(obj.rgba),
    )
    if obj.texture is not None:
        spec.add_texture(name=visual, file=str(obj.texture), type=mujoco.mjtTexture.mjTEXTURE_2D)
        material = spec.add_material(name=visual)
        material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = visual
        vis.material = visual
        vis.rgba = [1.0, 1.0, 1.0, 1.0]
    return body
