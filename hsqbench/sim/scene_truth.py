"""The simulator's truth about the objects on the table, as the oracle reads it.

Only the privileged oracle planner and the graspability check (:mod:`hsqbench.planner.oracle`)
see this; perceiving planners get the cloud alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import mujoco
import numpy as np

from hsqbench.planner.truth import ObjectTruth, SceneTruth


def object_truth(model: mujoco.MjModel, data: mujoco.MjData, name: str, geoms) -> ObjectTruth:
    """One object's collision hulls (mesh geoms) in the world frame now."""
    hulls = []
    for g in geoms:
        mesh = model.geom_dataid[g]
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH or mesh < 0:
            continue
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        local = model.mesh_vert[start : start + count].astype(float)
        hulls.append(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])
    return ObjectTruth(name, tuple(hulls))


def scene_truth(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    geom_ids: dict[str, np.ndarray],
    names: Sequence[str],
    support_plane: Sequence[float],
) -> SceneTruth:
    """The objects ``names`` (those on the table) as :class:`SceneTruth`."""
    mujoco.mj_kinematics(model, data)
    objects = tuple(object_truth(model, data, n, geom_ids[n]) for n in names)
    plane = tuple(float(x) for x in support_plane)
    return SceneTruth(objects, (plane[0], plane[1], plane[2], plane[3]))
