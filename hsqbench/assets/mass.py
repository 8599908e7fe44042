"""Build step 3: mass properties of the posed solid (see :mod:`hsqbench.assets.build`)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import trimesh

from hsqbench.assets.build_spec import AssetError, AssetWarning
from hsqbench.assets.mesh_prep import is_closed_oriented

# --- 3. mass properties --------------------------------------------------------------------------


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
