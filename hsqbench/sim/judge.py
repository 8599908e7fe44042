"""What the simulation shows during an attempt: contacts, the object in the hand, the bin.

:class:`SceneProbe` answers the questions the trial runner asks while the arm moves, from the
simulator's state (ground truth: the judge is the simulator, not the robot's sensors):

- contact forces between the robot and the table or bin, and between the robot and each object;
- which object the two fingers hold (in contact with both finger bodies);
- where an object is relative to the TCP (slip), how high it has been lifted, its lowest point;
- whether an object lies inside the bin, on the table, or has fallen off.

Normal contact forces come from the constraint solver: for elliptic friction cones the first
constraint row of a contact is its normal force (``efc_force[efc_address]``); for pyramidal cones
``mj_contactForce`` is used.

The thresholds live in :class:`JudgeConfig` (``judge:`` in ``configs/trial.yaml``) and are applied
here, by the rules at the end of this module (:class:`HoldWatch`, :func:`approach_watch`,
:func:`judge_closed`); the trial runner calls them on the way.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.outcome import Outcome
from hsqbench.sim.robot import Panda


@dataclass(frozen=True)
class JudgeConfig:
    """Thresholds of the outcome rules (reasons in ``configs/trial.yaml``).

    Attributes:
        table_contact_force_n: a robot-table (or bin) contact above this before the fingers close
            is a collision.
        object_contact_force_n: a robot-object contact above this counts as a push.
        pushed_distance_m: an object pushed farther than this before closing is a collision.
        empty_width_m: fingers closer than this after closing hold nothing.
        slip_distance_m: an object farther than this from where it sat in the hand is lost.
        lost_time_s: an object out of contact with a finger for this long is lost.
        lifted_height_m: an object raised more than this was lifted (a loss is then ``dropped``).
        off_table_below_m: an object whose centre of mass is this far below the table top has
            fallen off the table.
    """

    table_contact_force_n: float = 5.0
    object_contact_force_n: float = 2.0
    pushed_distance_m: float = 0.02
    empty_width_m: float = 0.002
    slip_distance_m: float = 0.03
    lost_time_s: float = 0.1
    lifted_height_m: float = 0.02
    off_table_below_m: float = 0.05

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            if not value > 0:
                raise ValueError(f"judge.{name} must be positive, got {value}")


@dataclass(frozen=True)
class Box:
    """Axis-aligned box ``[lo, hi]`` (3,) in world metres."""

    lo: NDArray[np.float64]
    hi: NDArray[np.float64]

    def contains(self, p: NDArray[np.float64]) -> bool:
        return bool(np.all(p >= self.lo) and np.all(p <= self.hi))


class SceneProbe:
    """Queries on a scene's simulation state.

    Args:
        model: the compiled scene.
        panda: robot handles.
        object_bodies: object name -> body id.
        obstacle_geoms: table top and bin geoms.
        bin_box: the bin's inside.
        workspace_box: where an object takes part in a round: the cameras' view of the table
            (x, y) and the height band above the table top (z).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        panda: Panda,
        object_bodies: dict[str, int],
        obstacle_geoms: NDArray[np.int_],
        bin_box: Box,
        workspace_box: Box,
    ) -> None:
        self.model = model
        self.panda = panda
        self.object_bodies = dict(object_bodies)
        self.names = list(object_bodies)
        self.body_ids = np.array([object_bodies[n] for n in self.names], dtype=int)
        self.bin_box = bin_box
        self.workspace_box = workspace_box
        self.elliptic = model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
        # Per geom: -1 robot, -2 obstacle, k >= 0 object index, -3 anything else.
        kind = np.full(model.ngeom, -3, dtype=int)
        kind[np.isin(model.geom_bodyid, panda.body_ids)] = -1
        kind[np.asarray(obstacle_geoms, dtype=int)] = -2
        for k, b in enumerate(self.body_ids):
            kind[model.geom_bodyid == b] = k
        self.geom_kind = kind
        self.finger_of_geom = np.full(model.ngeom, -1, dtype=int)
        for side, fid in enumerate(panda.finger_body_ids):
            self.finger_of_geom[model.geom_bodyid == fid] = side
        self._wrench = np.zeros(6)
        self._free_adr = {
            n: int(model.jnt_qposadr[model.body_jntadr[b]]) for n, b in object_bodies.items()
        }
        self._geoms = {n: np.flatnonzero(model.geom_bodyid == b) for n, b in object_bodies.items()}
        self._collision_geoms = {
            n: g[(model.geom_contype[g] > 0) | (model.geom_conaffinity[g] > 0)]
            for n, g in self._geoms.items()
        }

    # ---- contacts ------------------------------------------------------------------------------
    def _contacts(self, data: mujoco.MjData) -> tuple[NDArray, NDArray, NDArray]:
        """(geom1, geom2, normal force) of the active contacts."""
        n = data.ncon
        if n == 0:
            e = np.zeros(0, dtype=int)
            return e, e, np.zeros(0)
        con = data.contact
        g1, g2 = con.geom1[:n].copy(), con.geom2[:n].copy()
        adr = con.efc_address[:n]
        if self.elliptic:
            force = np.where(adr >= 0, data.efc_force[np.maximum(adr, 0)], 0.0)
        else:
            force = np.zeros(n)
            for i in np.flatnonzero(adr >= 0):
                mujoco.mj_contactForce(self.model, data, int(i), self._wrench)
                force[i] = self._wrench[0]
        return g1, g2, force

    def robot_forces(self, data: mujoco.MjData) -> tuple[float, NDArray[np.float64], str]:
        """Largest robot-obstacle normal force (N), per object the largest robot-object normal
        force (N) in the current contacts, and the robot body in the strongest obstacle
        contact (``""`` if none)."""
        g1, g2, f = self._contacts(data)
        per_object = np.zeros(len(self.names))
        if len(f) == 0:
            return 0.0, per_object, ""
        k1, k2 = self.geom_kind[g1], self.geom_kind[g2]
        robot1, robot2 = k1 == -1, k2 == -1
        other = np.where(robot1, k2, np.where(robot2, k1, -3))
        robot_any = robot1 ^ robot2
        table = robot_any & (other == -2)
        body = ""
        table_force = 0.0
        if table.any():
            i = int(np.flatnonzero(table)[np.argmax(f[table])])
            table_force = float(f[i])
            robot_geom = g1[i] if robot1[i] else g2[i]
            body = self.model.body(self.model.geom_bodyid[robot_geom]).name
        obj = robot_any & (other >= 0)
        if obj.any():
            np.maximum.at(per_object, other[obj], f[obj])
        return table_force, per_object, body

    def finger_contacts(self, data: mujoco.MjData) -> NDArray[np.bool_]:
        """(n_objects, 2): object k touches the left / right finger."""
        out = np.zeros((len(self.names), 2), dtype=bool)
        n = data.ncon
        if n == 0:
            return out
        g1, g2 = data.contact.geom1[:n], data.contact.geom2[:n]
        for a, b in ((g1, g2), (g2, g1)):
            side = self.finger_of_geom[a]
            k = self.geom_kind[b]
            hit = (side >= 0) & (k >= 0)
            out[k[hit], side[hit]] = True
        return out

    def held_objects(self, data: mujoco.MjData) -> list[str]:
        """Objects touching both fingers."""
        both = self.finger_contacts(data).all(axis=1)
        return [self.names[k] for k in np.flatnonzero(both)]

    def on_hand(self, data: mujoco.MjData, name: str) -> bool:
        """Whether the object touches a finger (after an opening: hooked on it or wedged
        between the open pads)."""
        return bool(self.finger_contacts(data)[self.names.index(name)].any())

    def on_robot(self, data: mujoco.MjData) -> list[str]:
        """Objects touching any robot part."""
        return [self.names[k] for k in np.flatnonzero(self.robot_forces(data)[1] > 0.0)]

    # ---- object state --------------------------------------------------------------------------
    def position(self, data: mujoco.MjData, name: str) -> NDArray[np.float64]:
        """World position of the object's centre of mass, metres."""
        return data.xipos[self.object_bodies[name]].copy()

    def positions(self, data: mujoco.MjData) -> NDArray[np.float64]:
        """(n_objects, 3) centres of mass."""
        return data.xipos[self.body_ids].copy()

    def tcp_in_object(self, data: mujoco.MjData, name: str) -> NDArray[np.float64]:
        """The TCP (grasp centre) in the object's body frame, metres: the material point of the
        object held between the pads."""
        b = self.object_bodies[name]
        r = data.xmat[b].reshape(3, 3)
        return r.T @ (data.site_xpos[self.panda.tcp_site_id] - data.xpos[b])

    def slip(self, data: mujoco.MjData, name: str, point: NDArray[np.float64]) -> float:
        """How far the object's material ``point`` (body frame, e.g. from :meth:`tcp_in_object`
        at the grasp) is from the TCP now, metres: translation in the hand, not the swing of a
        long object pivoting between the pads."""
        b = self.object_bodies[name]
        world = data.xpos[b] + data.xmat[b].reshape(3, 3) @ point
        return float(np.linalg.norm(world - data.site_xpos[self.panda.tcp_site_id]))

    def lowest_z(self, data: mujoco.MjData, name: str) -> float:
        """Lowest world z of the object's collision geoms' bounding boxes, metres."""
        z = np.inf
        m = self.model
        for g in self._collision_geoms[name]:
            centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
            row = data.geom_xmat[g].reshape(3, 3)[2]
            z = min(z, data.geom_xpos[g, 2] + row @ centre - np.abs(row) @ half)
        return float(z)

    def nearest_object(self, data: mujoco.MjData, point: NDArray[np.float64]) -> str:
        """The object whose collision-geom bounding box centre is nearest to ``point``."""
        best, name = np.inf, self.names[0] if self.names else ""
        for n, geoms in self._collision_geoms.items():
            centres = data.geom_xpos[geoms] + np.einsum(
                "gij,gj->gi",
                data.geom_xmat[geoms].reshape(-1, 3, 3),
                self.model.geom_aabb[geoms, :3],
            )
            d = float(np.min(np.linalg.norm(centres - point, axis=1)))
            if d < best:
                best, name = d, n
        return name

    def in_bin(self, data: mujoco.MjData, name: str) -> bool:
        return self.bin_box.contains(self.position(data, name))

    def in_workspace(self, data: mujoco.MjData, name: str) -> bool:
        return self.workspace_box.contains(self.position(data, name))

    def set_free_pose(
        self, data: mujoco.MjData, name: str, position: NDArray[np.float64], quat=(1, 0, 0, 0)
    ) -> None:
        """Teleport an object (its body frame) and stop it."""
        adr = self._free_adr[name]
        data.qpos[adr : adr + 3] = position
        data.qpos[adr + 3 : adr + 7] = quat
        b = self.object_bodies[name]
        dof = self.model.jnt_dofadr[self.model.body_jntadr[b]]
        data.qvel[dof : dof + 6] = 0.0


# ---- the outcome rules (the thresholds of JudgeConfig applied) ----------------------------------


class HoldWatch:
    """Watches that an object stays in the hand: touching both fingers, and the point of it
    that was between the pads when the hand closed still there (it may pivot about it).
    Called each control step; returns why the object is lost, or None."""

    def __init__(
        self, probe: SceneProbe, data: mujoco.MjData, name: str, config: JudgeConfig
    ) -> None:
        self.probe, self.data, self.name, self.config = probe, data, name, config
        self.k = probe.names.index(name)
        self.point = probe.tcp_in_object(data, name)
        self.z0 = float(probe.position(data, name)[2])
        self.max_rise = 0.0
        self.out_since: float | None = None

    def __call__(self) -> str | None:
        probe, d, j = self.probe, self.data, self.config
        self.max_rise = max(self.max_rise, float(probe.position(d, self.name)[2]) - self.z0)
        touching = probe.finger_contacts(d)[self.k]
        if touching.all():
            self.out_since = None
        elif self.out_since is None:
            self.out_since = float(d.time)
        if self.out_since is not None and d.time - self.out_since >= j.lost_time_s:
            side = "left" if not touching[0] else "right"
            return f"{self.name} left the {side} finger"
        slip = probe.slip(d, self.name, self.point)
        if slip > j.slip_distance_m:
            return f"{self.name} slipped {slip * 100:.1f} cm in the hand"
        return None

    def loss(self, reason: str, during: str) -> tuple[Outcome, str]:
        """The outcome of losing the object ``during`` the lift: ``dropped`` once it had risen
        ``lifted_height_m``, else ``empty_grasp`` (it was never lifted)."""
        if self.max_rise > self.config.lifted_height_m:
            return Outcome.DROPPED, f"during the {during}: {reason}"
        return Outcome.EMPTY_GRASP, f"not lifted: {reason}"


def approach_watch(
    probe: SceneProbe, data: mujoco.MjData, start: NDArray[np.float64], config: JudgeConfig
) -> Callable[[], str | None]:
    """A per-step check before the fingers close: why the motion is a collision (the robot
    presses the table or bin, or pushes an object away from ``start``, its positions when the
    motion began), or None."""
    j = config
    names = probe.names

    def watch() -> str | None:
        table_f, obj_f, body = probe.robot_forces(data)
        if table_f > j.table_contact_force_n:
            return f"{body} hit the table or bin ({table_f:.0f} N)"
        moved = np.linalg.norm(probe.positions(data) - start, axis=1)
        pushed = (obj_f > j.object_contact_force_n) & (moved > j.pushed_distance_m)
        if pushed.any():
            k = int(np.argmax(np.where(pushed, moved, -1.0)))
            return f"hand pushed {names[k]} {moved[k] * 100:.1f} cm ({obj_f[k]:.0f} N)"
        return None

    return watch


def judge_closed(width_m: float, held: list[str], config: JudgeConfig) -> str | None:
    """Why the closed hand holds nothing (an ``empty_grasp``), or None: the fingers closed to
    within ``empty_width_m``, or no object touches both fingers."""
    if width_m < config.empty_width_m:
        return f"fingers closed fully ({width_m * 1000:.1f} mm)"
    if not held:
        return f"no object between the fingers ({width_m * 1000:.0f} mm)"
    return None
