"""The simulator's truth about the objects on the table, as the oracle reads it.

Only the privileged oracle planner and the graspability check (:mod:`hsqbench.planner.oracle`)
see this; perceiving planners get the cloud alone.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray
from scipy.spatial import ConvexHull

from hsqbench.planner.truth import HandTruth, ObjectTruth, SceneTruth

_CORNERS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)


def object_truth(model: mujoco.MjModel, data: mujoco.MjData, name: str, geoms) -> ObjectTruth:
    """One object's collision hulls (mesh geoms) in the world frame now."""
    hulls, friction = [], []
    for g in geoms:
        mesh = model.geom_dataid[g]
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH or mesh < 0:
            continue
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        local = model.mesh_vert[start : start + count].astype(float)
        hulls.append(local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g])
        friction.append(float(model.geom_friction[g, 0]))
    return ObjectTruth(name, tuple(hulls), max(friction) if friction else None)


def _geom_vertices(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> NDArray[np.float64]:
    """World vertices of a box or mesh geom (MuJoCo collides with a mesh's convex hull, so its
    vertices bound it as exactly as the hull's)."""
    if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX:
        local = _CORNERS * model.geom_size[g]
    elif model.geom_type[g] == mujoco.mjtGeom.mjGEOM_MESH:
        mesh = model.geom_dataid[g]
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        local = model.mesh_vert[start : start + count].astype(float)
        local = local[ConvexHull(local).vertices]
    else:
        raise ValueError(
            f"hand geom {g}: only boxes and meshes are read, got type {model.geom_type[g]}"
        )
    return local @ data.geom_xmat[g].reshape(3, 3).T + data.geom_xpos[g]


def hand_truth(model: mujoco.MjModel, data: mujoco.MjData, panda: Any) -> HandTruth:
    """The hand's collision geoms (hand body, fingers, pads: the boxes on the fingers) in the
    TCP frame, each finger moved so its pad face lies on x = 0 (:class:`HandTruth`)."""
    mujoco.mj_kinematics(model, data)
    site = panda.tcp_site_id
    rot, origin = data.site_xmat[site].reshape(3, 3), data.site_xpos[site]
    collides = (model.geom_contype > 0) | (model.geom_conaffinity > 0)

    def part(body: int, pads_only: bool = False) -> NDArray[np.float64]:
        geoms = np.flatnonzero((model.geom_bodyid == body) & collides)
        if pads_only:
            geoms = geoms[model.geom_type[geoms] == mujoco.mjtGeom.mjGEOM_BOX]
        pts = np.concatenate([_geom_vertices(model, data, int(g)) for g in geoms])
        return (pts - origin) @ rot

    fingers, pads = [], []
    for body in panda.finger_body_ids:
        fingers.append(part(int(body)))
        pads.append(part(int(body), pads_only=True))
    left = int(np.argmax([f[:, 0].mean() for f in fingers]))
    right = 1 - left
    left_face, right_face = pads[left][:, 0].min(), pads[right][:, 0].max()
    pad_boxes = np.flatnonzero(
        np.isin(model.geom_bodyid, panda.finger_body_ids)
        & collides
        & (model.geom_type == mujoco.mjtGeom.mjGEOM_BOX)
    )
    z = np.concatenate(pads)[:, 2]
    return HandTruth(
        left_finger=fingers[left] - [left_face, 0.0, 0.0],
        right_finger=fingers[right] - [right_face, 0.0, 0.0],
        palm=part(int(panda.hand_body_id)),
        pad_z_m=(float(z.min()), float(z.max())),
        pad_friction=float(model.geom_friction[pad_boxes, 0].max()),
    )


@functools.cache
def panda_hand(robot_config: str = "robot") -> HandTruth:
    """The Panda's hand of ``configs/<robot_config>.yaml``, compiled alone (for a scene made
    outside the simulator)."""
    from hsqbench.sim.robot import Panda, load_panda_spec, load_robot_config

    model = load_panda_spec(load_robot_config(robot_config)).compile()
    return hand_truth(model, mujoco.MjData(model), Panda(model, prefix=""))


def scene_truth(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    geom_ids: dict[str, np.ndarray],
    names: Sequence[str],
    support_plane: Sequence[float],
    seed: int = 0,
    panda: Any = None,
) -> SceneTruth:
    """The objects ``names`` (those on the table) as :class:`SceneTruth` (``seed``: its field),
    with the hand of ``panda`` (:class:`hsqbench.sim.robot.Panda`) when given."""
    mujoco.mj_kinematics(model, data)
    objects = tuple(object_truth(model, data, n, geom_ids[n]) for n in names)
    plane = tuple(float(x) for x in support_plane)
    hand = None if panda is None else hand_truth(model, data, panda)
    return SceneTruth(objects, (plane[0], plane[1], plane[2], plane[3]), seed, hand)
