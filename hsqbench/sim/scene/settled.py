"""A composed scene compiled with the arm at home and its objects settled (every kind's last step)."""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from hsqbench.sim.physics import PhysicsConfig
from hsqbench.sim.robot import Panda, RobotConfig
from hsqbench.sim.scene.info import INITIAL_KEY, OBJECT_PREFIX
from hsqbench.sim.scene.world import come_to_rest


@dataclass
class Settled:
    """The compiled scene at rest. ``settle_time_s`` / ``max_speed``: :func:`~hsqbench.sim.scene.world.come_to_rest`'s answer."""

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    panda: Panda
    bodies: dict[str, str]
    body_ids: dict[str, int]
    settle_time_s: float
    max_speed: float


def compile_settled(
    spec: mujoco.MjSpec, names: list[str], robot: RobotConfig, physics: PhysicsConfig
) -> Settled:
    """Compile ``spec`` (objects ``names``), hold the arm at home, settle, and store the rest
    state as keyframe ``initial`` (in the model; the spec's keyframe stays empty)."""
    spec.add_key(name=INITIAL_KEY)
    model = spec.compile()
    data = mujoco.MjData(model)
    panda = Panda(model, robot.prefix)
    panda.reset_home(data)
    mujoco.mj_forward(model, data)
    bodies = {n: OBJECT_PREFIX + n for n in names}
    body_ids = {n: model.body(b).id for n, b in bodies.items()}
    settle_s, speed = come_to_rest(model, data, np.array(list(body_ids.values())), physics)
    key = model.key(INITIAL_KEY).id
    model.key_qpos[key] = data.qpos
    model.key_qvel[key] = 0.0
    model.key_ctrl[key] = data.ctrl
    model.key_time[key] = 0.0
    return Settled(spec, model, data, panda, bodies, body_ids, settle_s, speed)
