"""The harness's own clouds of isolated YCB objects, for the speed benchmarks (not run by itself).

:func:`observe` builds one isolated scene (``build_scene("isolated", [name], seed)``), observes it
with the scene's two depth cameras and the configured sensor model (``configs/perception.yaml``)
and samples the object's true visual mesh in its settled pose (``truth``: what
``bench_cleaning.py`` measures the cleaned cloud against). Clouds are cached under
``cache_dir()/harness_clouds``, keyed by the scene and perception configs, the object, the seed
and the sensor model, so a benchmark renders each cloud once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

import numpy as np

from hsqbench.config import to_dict
from hsqbench.settings import cache_dir

#: Spacing of the ground-truth mesh samples, metres (the fused cloud's 2 mm voxel).
GT_SPACING_M = 0.002
#: Part of the cache key: bump when the cached content changes.
CACHE_VERSION = 3


def mesh_samples(model, data, body_id: int, rng: np.random.Generator):
    """World points on the visual meshes of a body, about one per GT_SPACING_M^2 of area, and
    their unit normals (the triangles' winding: outward for the YCB meshes)."""
    import mujoco

    from hsqbench.sim.objects import VISUAL_GROUP

    points, normals = [], []
    for g in np.flatnonzero(model.geom_bodyid == body_id):
        if model.geom_group[g] != VISUAL_GROUP or model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        m = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[m], model.mesh_vertnum[m]
        f0, nf = model.mesh_faceadr[m], model.mesh_facenum[m]
        verts = model.mesh_vert[v0 : v0 + nv].astype(float)
        tri = verts[model.mesh_face[f0 : f0 + nf]]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = 0.5 * np.linalg.norm(cross, axis=1)
        n = int(np.ceil(area.sum() / GT_SPACING_M**2))
        pick = rng.choice(nf, size=n, p=area / area.sum())
        a, b = rng.random((2, n))
        swap = a + b > 1
        a[swap], b[swap] = 1 - a[swap], 1 - b[swap]
        t = tri[pick]
        local = t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0])
        rot = data.geom_xmat[g].reshape(3, 3)
        points.append(data.geom_xpos[g] + local @ rot.T)
        unit = cross[pick] / np.maximum(2.0 * area[pick], 1e-18)[:, None]
        normals.append(unit @ rot.T)
    return np.concatenate(points), np.concatenate(normals)


def observe(
    name: str, seed: int, sensor: str | None, refresh: bool, scene: str | None = None
) -> dict[str, np.ndarray]:
    """Cloud, table plane and ground-truth mesh samples of one isolated scene (cached).

    ``scene``: a scene config name or YAML path (default ``configs/scene.yaml``)."""
    from hsqbench.sim.perception import Perception, load_perception_config
    from hsqbench.sim.scene import build_scene, load_scene_config

    pcfg = load_perception_config()
    if sensor is not None:
        pcfg = dataclasses.replace(pcfg, sensor_model=sensor)
    scfg = load_scene_config("scene" if scene is None else scene)
    key = json.dumps([CACHE_VERSION, to_dict(scfg), to_dict(pcfg), name, seed], sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    path = cache_dir() / "harness_clouds" / f"{name}_s{seed}_{pcfg.sensor_model}_{digest}.npz"
    if path.exists() and not refresh:
        with np.load(path) as f:
            return dict(f)
    model, data, info = build_scene("isolated", [name], seed=seed, scene_config=scfg)
    rng = np.random.default_rng(seed)
    with Perception.from_scene(model, info, rng=rng, config=pcfg) as perception:
        obs = perception.observe(data, rng)
    truth, normals = mesh_samples(
        model, data, info.object_body_ids[name], np.random.default_rng(seed)
    )
    out = {
        "points": obs.points,
        "camera_index": obs.camera_index,
        "support_plane": np.asarray(info.support_plane, float),
        "truth": truth,
        "truth_normals": normals,
        "camera_positions": obs.camera_positions,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    return out


def object_names(choice: list[str] | None) -> list[str]:
    """Names for ``--objects``: ``paper``, ``unseen``, ``all`` or the names themselves."""
    from hsqbench.assets.library import ycb_names
    from hsqbench.experiment.config import YCB_OBJECTS

    paper = list(YCB_OBJECTS)
    if not choice or choice == ["paper"]:
        return paper
    if choice == ["all"]:
        return ycb_names()
    if choice == ["unseen"]:
        return [n for n in ycb_names() if n not in paper]
    return choice
