"""A model's static description as plain data, to check that a refactor of how a scene is
composed leaves the compiled model unchanged (``tests/data/scene_reference.json`` holds that of
the scene before the static world moved into ``scenes/*.xml``)."""

from __future__ import annotations

import hashlib

import mujoco
import numpy as np

# The static world: geoms of the world body, cameras, lights, materials and textures (the
# robot's too: the order in which parts are composed shows in their ids), options, visual.
WORLD_GEOM_FIELDS = (
    "geom_type", "geom_pos", "geom_quat", "geom_size", "geom_rgba", "geom_friction",
    "geom_contype", "geom_conaffinity", "geom_group", "geom_condim", "geom_solref",
    "geom_solimp", "geom_priority", "geom_margin", "geom_gap", "geom_matid",
)  # fmt: skip
FIELDS = (
    "cam_pos", "cam_quat", "cam_fovy", "cam_resolution", "cam_bodyid",
    "light_pos", "light_dir", "light_diffuse", "light_ambient", "light_specular",
    "light_castshadow", "light_type",
    "mat_rgba", "mat_texrepeat", "mat_reflectance", "mat_texid",
    "tex_type", "tex_height", "tex_width",
    "opt.timestep", "opt.gravity", "opt.impratio", "opt.cone", "opt.noslip_iterations",
    "vis.headlight.ambient", "vis.headlight.diffuse", "vis.headlight.specular",
    "vis.global_.offwidth", "vis.global_.offheight", "vis.quality.shadowsize",
    "vis.map.znear", "vis.map.zfar",
)  # fmt: skip

NAMED = {"camera": "ncam", "light": "nlight", "material": "nmat", "texture": "ntex"}


def _get(model: mujoco.MjModel, path: str):
    value = model
    for part in path.split("."):
        value = getattr(value, part)
    return np.asarray(value, dtype=float).round(9).tolist()


def model_fingerprint(model: mujoco.MjModel) -> dict:
    """The world body's geoms (names, sizes, poses, contact), cameras, lights, materials,
    textures (a digest of their pixels), options and visual settings."""
    world = np.flatnonzero(model.geom_bodyid == 0)
    out: dict = {
        f: np.asarray(getattr(model, f))[world].round(9).tolist() for f in WORLD_GEOM_FIELDS
    }
    out["world_geom_names"] = [model.geom(i).name for i in world]
    out["world_geom_ids"] = world.tolist()
    out.update({f: _get(model, f) for f in FIELDS})
    for kind, count in NAMED.items():
        out[f"{kind}_names"] = [getattr(model, kind)(i).name for i in range(getattr(model, count))]
    out["tex_data_sha256"] = hashlib.sha256(np.asarray(model.tex_data).tobytes()).hexdigest()
    return out
