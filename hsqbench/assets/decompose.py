"""Build step 4: convex decomposition with CoACD, hulls cleaned for MuJoCo (see
:mod:`hsqbench.assets.build`)."""

from __future__ import annotations

import time
import warnings
from dataclasses import asdict

import numpy as np
import trimesh

from hsqbench.assets.build_spec import AssetError, AssetWarning
from hsqbench.assets.config import CoacdConfig, HullConfig

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
