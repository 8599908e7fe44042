"""The Panda's geometry on a private copy of the simulation state: forward kinematics, the hand's
extent in the TCP frame, and the collision checks of an arm posture or motion against the
obstacles (table, bin; exact ``mj_geomDistance``) and against the perceived cloud (points in the
robot geoms' bounding boxes).

:class:`ArmGeometry` is the base of :class:`hsqbench.sim.ik.ArmIK`, which adds the solver; the
two share one ``mink.Configuration`` (its ``MjData`` is never the simulation's).
"""

from __future__ import annotations

from collections.abc import Iterable

import mink
import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from hsqbench.sim.ik_types import IKConfig, Pose
from hsqbench.sim.robot import Panda

__all__ = ["ArmGeometry"]


class ArmGeometry:
    """The Panda's kinematics and clearances on its own ``MjData``.

    Args:
        model: the compiled scene (or any model containing the Panda).
        panda: handles into ``model``.
        config: the IK settings (``clearance_m`` and ``link_clearance_m`` are used here).
        obstacle_geoms: geom ids the robot must keep ``clearance_m`` from (table, bin).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        panda: Panda,
        config: IKConfig,
        obstacle_geoms: Iterable[int] = (),
    ) -> None:
        self.model = model
        self.panda = panda
        self.config = config
        self.configuration = mink.Configuration(model)
        self.data = self.configuration.data
        self.obstacle_geoms = np.asarray(list(obstacle_geoms), dtype=int)
        robot = np.isin(model.geom_bodyid, panda.body_ids) & (
            (model.geom_contype > 0) | (model.geom_conaffinity > 0)
        )
        # The base link is welded to the table: only moving links can hit it.
        robot &= model.body_weldid[model.geom_bodyid] != 0
        self.robot_geoms = np.flatnonzero(robot)
        # Bodies rigid with the TCP: where they are follows from the target pose alone.
        link7 = model.body(panda.prefix + "link7").id
        self._rigid = np.array([panda.hand_body_id, *panda.finger_body_ids, link7])
        self._rigid_geom = np.isin(model.geom_bodyid[self.robot_geoms], self._rigid)
        self._required = np.where(self._rigid_geom, config.clearance_m, config.link_clearance_m)
        self._qpos_template = model.qpos0.copy()
        self._boxes: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    # ---- state ---------------------------------------------------------------------------------
    def sync(self, data: mujoco.MjData, gripper_width_m: float | None = None) -> None:
        """Copy the simulation's configuration (objects, fingers) into the IK state. With
        ``gripper_width_m`` the fingers are placed at that opening (e.g. fully open for an
        approach)."""
        q = data.qpos.copy()
        if gripper_width_m is not None:
            q[self.panda.finger_qpos_adr] = 0.5 * gripper_width_m
        self._qpos_template = q

    def _full_q(self, arm_q: NDArray[np.float64]) -> NDArray[np.float64]:
        q = self._qpos_template.copy()
        q[self.panda.arm_qpos_adr] = arm_q
        return q

    def forward(self, arm_q: ArrayLike) -> Pose:
        """TCP pose at the arm joint angles ``arm_q`` (7,)."""
        self.configuration.update(self._full_q(np.asarray(arm_q, dtype=float)))
        sid = self.panda.tcp_site_id
        return Pose(self.data.site_xpos[sid].copy(), self.data.site_xmat[sid].reshape(3, 3).copy())

    def clearance(self, arm_q: ArrayLike, distmax: float = 0.05) -> tuple[float, int, float]:
        """How far the robot at ``arm_q`` is from the obstacles, against what each part needs
        (``clearance_m`` for the hand, fingers and link7, ``link_clearance_m`` for links 1-6).

        Returns ``(margin, geom, distance)``: the smallest distance minus the part's required
        clearance over robot collision geoms (negative: too close), that geom (-1 if nothing is
        within ``distmax``) and its distance in metres (capped at ``distmax``). Only pairs whose
        bounding sphere (robot geom) and box (obstacle) come within ``distmax`` go to the exact
        ``mj_geomDistance``, which keeps a check at tens of microseconds."""
        self.configuration.update(self._full_q(np.asarray(arm_q, dtype=float)))
        best = (distmax, -1, distmax)
        if not len(self.obstacle_geoms):
            return best
        d, m = self.data, self.model
        g = self.robot_geoms
        centres = d.geom_xpos[g] + np.einsum(
            "gij,gj->gi", d.geom_xmat[g].reshape(-1, 3, 3), m.geom_aabb[g, :3]
        )
        radii = np.linalg.norm(m.geom_aabb[g, 3:], axis=1)
        lo, hi = self._obstacle_boxes()
        gap = np.maximum(np.maximum(lo[None] - centres[:, None], centres[:, None] - hi[None]), 0.0)
        bound = np.linalg.norm(gap, axis=2) - radii[:, None]
        for i, j in zip(*np.nonzero(bound < distmax), strict=True):
            dist = mujoco.mj_geomDistance(
                m, d, int(g[i]), int(self.obstacle_geoms[j]), distmax, None
            )
            margin = dist - self._required[i]
            if margin < best[0]:
                best = (float(margin), int(g[i]), float(dist))
        return best

    def hand_margin(self, arm_q: ArrayLike) -> float:
        """:meth:`clearance` margin of the hand, fingers and link7 alone, metres (their place
        follows from the TCP pose, so a deficit is fixed by moving the target, not the arm)."""
        self.configuration.update(self._full_q(np.asarray(arm_q, dtype=float)))
        worst = 0.05
        for i in np.flatnonzero(self._rigid_geom):
            for o in self.obstacle_geoms:
                dist = mujoco.mj_geomDistance(
                    self.model, self.data, int(self.robot_geoms[i]), int(o), 0.05, None
                )
                worst = min(worst, dist - self._required[i])
        return float(worst)

    def _obstacle_boxes(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """World axis-aligned boxes (lo, hi), each (n_obstacles, 3), of the (static) obstacles."""
        if self._boxes is None:
            d, m, o = self.data, self.model, self.obstacle_geoms
            rot = d.geom_xmat[o].reshape(-1, 3, 3)
            centre = d.geom_xpos[o] + np.einsum("gij,gj->gi", rot, m.geom_aabb[o, :3])
            half = np.einsum("gij,gj->gi", np.abs(rot), m.geom_aabb[o, 3:])
            self._boxes = (centre - half, centre + half)
        return self._boxes

    def sweep_clearance(self, qs: ArrayLike) -> tuple[float, int, float, int]:
        """:meth:`clearance` over joint configurations ``qs`` (N, 7) sampled along a motion:
        the worst (margin, geom, distance) and the index of that sample."""
        worst = (np.inf, -1, np.inf, 0)
        for k, q in enumerate(np.asarray(qs, dtype=float)):
            margin, g, dist = self.clearance(q)
            if margin < worst[0]:
                worst = (margin, g, dist, k)
        return worst

    def points_hit(
        self, qs: ArrayLike, points: ArrayLike, margin_m: float, min_points: int = 1
    ) -> tuple[int, int, int]:
        """First sample of the motion ``qs`` (N, 7) at which a robot collision geom's bounding
        box, grown by ``margin_m``, contains ``min_points`` or more of ``points`` (M, 3) (the
        perceived cloud: the objects as the robot knows them). Returns ``(sample, geom,
        n_points)``, or ``(-1, -1, 0)`` when the motion stays clear."""
        pts = np.asarray(points, dtype=float)
        if len(pts) == 0:
            return -1, -1, 0
        m, d, g = self.model, self.data, self.robot_geoms
        centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:] + margin_m
        # A point in a box lies within the box's half-diagonal of its centre: a geom whose
        # sphere misses the cloud's bounding box holds no point (most of them, most of the way),
        # and only the points in the sphere of a geom that reaches the cloud are tested (a
        # KD-tree query: the hand near a packed scene's cloud meets a few hundred of its points).
        reach = np.linalg.norm(half, axis=1) + 1e-9
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        every = min_points < 1  # then a sample with no point in any box is a hit too
        tree = cKDTree(pts)
        for k, q in enumerate(np.asarray(qs, dtype=float)):
            self.configuration.update(self._full_q(q))
            rot = d.geom_xmat[g].reshape(-1, 3, 3)
            box = d.geom_xpos[g] + np.einsum("gij,gj->gi", rot, centre)
            near = np.flatnonzero(
                every
                | (np.linalg.norm(np.maximum(np.maximum(lo - box, box - hi), 0.0), axis=1) <= reach)
            )
            if not len(near):
                continue
            in_sphere = tree.query_ball_point(box[near], reach[near])
            sizes = np.fromiter(map(len, in_sphere), dtype=np.intp, count=len(near))
            counts = np.zeros(len(near), dtype=np.intp)
            if sizes.any():
                idx = np.concatenate(in_sphere).astype(np.intp)
                slot = np.repeat(np.arange(len(near)), sizes)  # the near geom of each pair
                which = near[slot]
                # Each point in its geom's frame, relative to the box centre.
                local = np.einsum("nji,nj->ni", rot[which], pts[idx] - d.geom_xpos[g[which]])
                inside = np.all(np.abs(local - centre[which]) <= half[which], axis=1)
                counts = np.bincount(slot[inside], minlength=len(near))
            if counts.max() >= min_points:
                j = int(np.argmax(counts))  # the first of the most, as over all geoms
                return k, int(g[near[j]]), int(counts[j])
        return -1, -1, 0

    def hand_extent(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounding box ``(lo, hi)`` (3,) of the hand's collision geoms (hand, fingers as
        synced, and link7, all rigid with the TCP) in the TCP frame, metres."""
        self.configuration.update(self._full_q(self.panda.home_arm_q))
        d, sid = self.data, self.panda.tcp_site_id
        r_tcp, p_tcp = d.site_xmat[sid].reshape(3, 3), d.site_xpos[sid]
        signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
        pts = []
        for g in self.robot_geoms[np.isin(self.model.geom_bodyid[self.robot_geoms], self._rigid)]:
            centre, half = self.model.geom_aabb[g, :3], self.model.geom_aabb[g, 3:]
            local = centre + signs * half
            world = local @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]
            pts.append((world - p_tcp) @ r_tcp)
        pts = np.concatenate(pts)
        return pts.min(axis=0), pts.max(axis=0)
