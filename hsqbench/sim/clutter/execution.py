"""One grasp with the free hand, as VGN/GIGA's ``ClutterRemovalSim.execute_grasp`` runs it.

1. **Pre-grasp**: the open hand is put (teleported, at rest) with its TCP ``pregrasp_offset_m``
   back along the approach axis. Touching anything there (an object or the table) fails the
   grasp at once.
2. **Approach**: the TCP moves to the grasp in straight ``step_m`` steps at ``speed_mps``; the
   first contact stops it where it is. With ``allow_contact`` (their clutter-removal runs) the
   grasp goes on from there; without, the contact fails it.
3. **Close** with the arm hand's 70 N servo until the fingers stop (``close_time_s`` at most).
4. **Lift** ``retreat_m``: straight up when the approach is more than ``side_grasp_angle_deg``
   from straight down (a side grasp), else back along the approach; contacts do not stop it.
5. **Success** when the hand touches an object and the fingers are wider than
   ``min_width_fraction`` of the full opening (their ``check_success``). The object held (the
   one touching the hand nearest the TCP) is taken out of the world; the hand goes back to its
   parking place.

Their success test counts a contact with any body; here with an object (the table cannot be
touched 10 cm up). Outcomes: a contact at the pre-grasp or, without ``allow_contact``, on the
approach is ``collision_on_approach``; after closing, fingers at or below the width limit or
no object in the hand is ``empty_grasp``; an object held after closing but not after the lift
is ``dropped``.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.clutter.world import ClutterWorld
from hsqbench.sim.outcome import Outcome

Array = NDArray[np.float64]


@dataclass
class HandResult:
    """What the hand's grasp found: outcome, the object it concerned, detail, simulated time."""

    outcome: Outcome
    target: str
    detail: str
    sim_time_s: float
    width_m: float


def retreat_position(position: Array, rotation: Array, lift_m: float, side_deg: float) -> Array:
    """Where the TCP goes after closing: ``lift_m`` straight up for an approach more than
    ``side_deg`` from straight down, else ``lift_m`` back along the approach."""
    approach = rotation[:, 2]
    angle = np.degrees(np.arccos(np.clip(np.dot(approach, [0.0, 0.0, -1.0]), -1.0, 1.0)))
    if angle > side_deg:
        return position + np.array([0.0, 0.0, lift_m])
    return position - lift_m * approach


def _objects_touched(world: ClutterWorld) -> list[str]:
    bodies = world.hand.touching(world.data)
    return [n for n in world.in_play if world.body_ids[n] in set(bodies.tolist())]


def move_tcp(
    world: ClutterWorld,
    start: Array,
    target: Array,
    rotation: Array,
    abort_on_contact: bool,
) -> bool:
    """Their ``move_tcp_xyz``: the mocap target in ``step_m`` steps at ``speed_mps``, the
    simulation run for each step's duration. Returns whether a contact stopped it."""
    ex = world.config.hand
    diff = target - start
    n = int(np.linalg.norm(diff) / ex.step_m)
    if n == 0:
        return False
    step = diff / n
    nsteps = max(1, int(np.linalg.norm(step) / ex.speed_mps / world.model.opt.timestep))
    here = start.copy()
    for _ in range(n):
        here = here + step
        world.hand.set_target(world.data, here, rotation)
        mujoco.mj_step(world.model, world.data, nstep=nsteps)
        if abort_on_contact and len(world.hand.touching(world.data)):
            return True
    return False


def close_hand(world: ClutterWorld) -> float:
    """Close with the full force until the fingers stop; returns the width, metres."""
    ex, hand, d = world.config.hand, world.hand, world.data
    hand.close_gripper(d)
    dt = world.model.opt.timestep
    chunk = max(1, round(0.05 / dt))
    prev = hand.gripper_width(d)
    t0 = d.time
    while d.time - t0 < ex.close_time_s:
        mujoco.mj_step(world.model, d, nstep=chunk)
        width = hand.gripper_width(d)
        if abs(width - prev) / (chunk * dt) < ex.gripper_still_mps and d.time - t0 > 0.1:
            break
        prev = width
    return hand.gripper_width(d)


def execute_hand_grasp(world: ClutterWorld, position: Array, rotation: Array) -> HandResult:
    """Run one grasp (TCP ``position``, rotation columns closing, third, approach) and judge
    it (module notes). The hand is parked again afterwards; a held object is taken out."""
    ex, hand, d = world.config.hand, world.hand, world.data
    position, rotation = np.asarray(position, float), np.asarray(rotation, float)
    t_start = d.time
    approach = rotation[:, 2]
    pre = position - ex.pregrasp_offset_m * approach
    lift = retreat_position(position, rotation, ex.retreat_m, ex.side_grasp_angle_deg)
    nearest = _nearest(world, position)

    def done(outcome: Outcome, target: str, detail: str) -> HandResult:
        width = hand.gripper_width(d)
        hand.teleport(d, np.array(ex.park_m), np.eye(3))
        return HandResult(outcome, target, detail, float(d.time - t_start), width)

    hand.teleport(d, pre, rotation)
    if len(hand.touching(d)):
        return done(
            Outcome.COLLISION_ON_APPROACH, nearest, "the hand touches something at the pre-grasp"
        )
    stopped = move_tcp(world, pre, position, rotation, abort_on_contact=True)
    note = ""
    if stopped:
        if not ex.allow_contact:
            return done(Outcome.COLLISION_ON_APPROACH, nearest, "contact on the approach")
        gap = float(np.linalg.norm(position - hand.tcp_position(d)))
        note = f" (approach stopped by a contact {gap * 100:.1f} cm short)"
    width = close_hand(world)
    held = _objects_touched(world)
    limit = ex.min_width_fraction * hand.max_width()
    if width <= limit or not held:
        why = f"closed to {width * 1000:.1f} mm" if width <= limit else "no object in the hand"
        return done(Outcome.EMPTY_GRASP, nearest, why + note)
    tcp = hand.tcp_position(d)
    target = min(held, key=lambda n: float(np.linalg.norm(world.com(n) - tcp)))
    move_tcp(world, hand.tcp_position(d), lift, rotation, abort_on_contact=False)
    held = _objects_touched(world)
    width = hand.gripper_width(d)
    if width <= limit or not held:
        return done(Outcome.DROPPED, target, "lost during the lift" + note)
    target = min(held, key=lambda n: float(np.linalg.norm(world.com(n) - hand.tcp_position(d))))
    result = done(Outcome.SUCCESS, target, "held after the lift" + note)
    world.park(target)
    return result


def _nearest(world: ClutterWorld, point: Array) -> str:
    if not world.in_play:
        return ""
    return min(world.in_play, key=lambda n: float(np.linalg.norm(world.com(n) - point)))
