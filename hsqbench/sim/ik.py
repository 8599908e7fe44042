"""Inverse kinematics of the Panda's TCP with mink, on a private copy of the simulation state.

A target is a :class:`Pose` of the TCP site (``tcp``: x = closing axis, z = approach axis, at the
grasp centre), so a planner grasp ``(rotation, position)`` is a TCP target as is.

The solver is mink's differential IK iterated to convergence (Gauss-Newton with
Levenberg-Marquardt damping). Each iteration solves a QP for the joint step ``dq``: minimise
``|J dq + e|^2_W + c_p |q + dq - q_home|^2``, with ``e`` the 6-D pose error of the TCP
(``mink.FrameTask``) and a light posture term (``mink.PostureTask``) that settles the seventh
degree of freedom near home, subject to

- ``mink.ConfigurationLimit``: every joint stays inside its range (and a solution within half of
  ``joint_limit_margin_rad`` of a limit is refused afterwards);
- ``mink.VelocityLimit``: no joint moves more than ``max_step_rad`` per iteration (the
  integration step is 1, so a velocity is a step). A full Gauss-Newton step toward a target
  40 cm away jumps into a far, often joint-limited, branch; small steps follow the error down;
- ``mink.CollisionAvoidanceLimit`` between the arm links (link1-link6) and the table and bin:
  the elbow and forearm keep ``link_clearance_m`` from them while the arm moves toward a low
  target.

Only the arm moves: the posture cost is zero on every other degree of freedom and the frame task
does not depend on them, so the LM damping keeps them fixed (object and finger coordinates stay
as copied from the simulation).

Acceptance: a solution counts only when the TCP is within ``position_tolerance_m`` and
``orientation_tolerance_deg`` of the target, the hand, fingers and link7 stay ``clearance_m`` and
links 1-6 ``link_clearance_m`` from the table and bin (``mj_geomDistance`` after solving; for the
hand and link7, which are rigid with the TCP, this is a property of the target itself). Restarts
begin at the caller's seed, then at the postures of a seed library (random postures whose TCP
pose is nearest the target: Gauss-Newton from home drifts into twisted branches for side grasps,
a nearby posture does not), then home turned toward the target, home, and random postures around
home from the caller's generator; a target reached with the hand in an obstacle twice is given
up early.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import mink
import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.sim.ik_types import (
    FLIP_ABOUT_APPROACH,
    IKConfig,
    IKSolution,
    PathSolution,
    Pose,
    line_poses,
    rotation_angle_deg,
)
from hsqbench.sim.robot import Panda

__all__ = [
    "FLIP_ABOUT_APPROACH",
    "LIBRARY_SEED",
    "ArmIK",
    "IKConfig",
    "IKSolution",
    "PathSolution",
    "Pose",
    "line_poses",
    "rotation_angle_deg",
]

#: Seed of the posture library's random draw (fixed: the library is part of the solver).
LIBRARY_SEED = 20240917
_LIBRARIES: dict[tuple, tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]] = {}


class ArmIK:
    """IK of the Panda's TCP on its own ``MjData`` (the simulation's data is never touched).

    Args:
        model: the compiled scene (or any model containing the Panda).
        panda: handles into ``model``.
        config: solver settings.
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
        self.frame_task = mink.FrameTask(
            panda.tcp_site_id,
            "site",
            position_cost=config.position_cost,
            orientation_cost=config.orientation_cost,
            lm_damping=config.lm_damping,
        )
        cost = np.zeros(model.nv)
        cost[panda.arm_dof_adr] = config.posture_cost
        self.posture_task = mink.PostureTask(model, cost=cost)
        self.limits = [
            mink.ConfigurationLimit(model),
            mink.VelocityLimit(model, {n: config.max_step_rad for n in panda.arm_joint_names}),
        ]
        self.lower, self.upper = model.jnt_range[
            [model.joint(n).id for n in panda.arm_joint_names]
        ].T.copy()
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
        links = self.robot_geoms[~np.isin(model.geom_bodyid[self.robot_geoms], self._rigid)]
        if len(links) and len(self.obstacle_geoms) and config.link_clearance_m > 0:
            # Keeps the elbow and forearm off the table while iterating (the hand's own
            # clearance is a property of the target, checked after solving).
            self.limits.append(
                mink.CollisionAvoidanceLimit(
                    model,
                    [([int(g) for g in links], [int(g) for g in self.obstacle_geoms])],
                    minimum_distance_from_collisions=config.link_clearance_m,
                    collision_detection_distance=config.link_detection_m,
                )
            )
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
        # sphere misses the cloud's bounding box holds no point (most of them, most of the way).
        reach = np.linalg.norm(half, axis=1) + 1e-9
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        every = min_points < 1  # then a sample with no point in any box is a hit too
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
            # Points in each near geom's frame, relative to its box centre: (G, M, 3).
            local = np.einsum("gji,gmj->gmi", rot[near], pts[None] - d.geom_xpos[g[near]][:, None])
            inside = np.all(np.abs(local - centre[near, None]) <= half[near, None], axis=2)
            counts = inside.sum(axis=1)
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

    # ---- solving -------------------------------------------------------------------------------
    def _errors(self, target: Pose) -> tuple[float, float]:
        sid = self.panda.tcp_site_id
        pos = self.data.site_xpos[sid]
        rot = self.data.site_xmat[sid].reshape(3, 3)
        return float(np.linalg.norm(pos - target.position)), rotation_angle_deg(
            rot, target.rotation
        )

    def _descend(
        self, target: Pose, q0: NDArray[np.float64], posture: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], float, float, int]:
        cfg = self.config
        conf = self.configuration
        m = cfg.joint_limit_margin_rad
        conf.update(self._full_q(np.clip(q0, self.lower + m, self.upper - m)))
        self.frame_task.set_target(
            mink.SE3.from_rotation_and_translation(
                mink.SO3.from_matrix(target.rotation), target.position
            )
        )
        self.posture_task.set_target(self._full_q(posture))
        tol_p = cfg.converged_fraction * cfg.position_tolerance_m
        tol_r = cfg.converged_fraction * cfg.orientation_tolerance_deg
        tasks = [self.frame_task, self.posture_task]
        ep, er = self._errors(target)
        it = 0
        history: list[float] = []
        for it in range(1, cfg.max_iterations + 1):
            if ep < tol_p and er < tol_r:
                it -= 1
                break
            # Stalled (a joint limit or an obstacle in the way): further iterations are wasted.
            err = ep / cfg.position_tolerance_m + er / cfg.orientation_tolerance_deg
            history.append(err)
            if (
                len(history) > cfg.stall_iterations
                and err > 0.99 * history[-1 - cfg.stall_iterations]
            ):
                break
            try:
                v = mink.solve_ik(
                    conf, tasks, 1.0, cfg.solver, damping=cfg.damping, limits=self.limits
                )
            except mink.NoSolutionFound:  # limits that cannot all hold: as stuck as a stall
                break
            conf.integrate_inplace(v, 1.0)
            ep, er = self._errors(target)
        q = conf.q[self.panda.arm_qpos_adr].copy()
        return q, ep, er, it

    def _library(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Seed library: ``(q (L, 7), tcp positions (L, 3), tcp rotations (L, 3, 3))`` of
        postures drawn uniformly inside the joint limits (less the margin) with a fixed seed,
        kept when the TCP lies above the table within reach. Built once per robot geometry and
        process (the arm's kinematics do not depend on the scene)."""
        m, p = self.model, self.panda
        bodies = np.asarray(p.body_ids)
        key = (
            m.body_pos[bodies].tobytes(),
            m.body_quat[bodies].tobytes(),
            m.site_pos[p.tcp_site_id].tobytes(),
            m.site_quat[p.tcp_site_id].tobytes(),
            self.config.seed_library_size,
            self.config.joint_limit_margin_rad,
        )
        if key not in _LIBRARIES:
            rng = np.random.default_rng(LIBRARY_SEED)
            margin = self.config.joint_limit_margin_rad
            qs = rng.uniform(
                self.lower + margin, self.upper - margin, size=(self.config.seed_library_size, 7)
            )
            pos, rot = np.empty((len(qs), 3)), np.empty((len(qs), 3, 3))
            sid = p.tcp_site_id
            for i, q in enumerate(qs):  # forward() without a validated Pose per posture
                self.configuration.update(self._full_q(q))
                pos[i], rot[i] = self.data.site_xpos[sid], self.data.site_xmat[sid].reshape(3, 3)
            keep = pos[:, 2] > 0.0
            _LIBRARIES[key] = (qs[keep], pos[keep], rot[keep])
        return _LIBRARIES[key]

    def seeds(
        self, target: Pose, q_seed: ArrayLike, n: int, rng: np.random.Generator | None
    ) -> list[NDArray[np.float64]]:
        """Restart seeds, in order: ``q_seed``; the ``library_seeds`` library postures whose
        TCP pose is nearest the target (position in units of 10 cm plus the Frobenius distance
        of the rotations); home turned about the base toward the target; home; then home plus
        Gaussian noise of ``seed_spread_rad`` from ``rng`` (none without ``rng``)."""
        home = self.panda.home_arm_q
        seeds = [np.asarray(q_seed, dtype=float)]
        k = min(self.config.library_seeds, n - 1)
        if k > 0 and self.config.seed_library_size > 0:
            qs, pos, rot = self._library()
            dist = np.linalg.norm(pos - target.position, axis=1) / 0.1 + np.linalg.norm(
                (rot - target.rotation).reshape(len(rot), 9), axis=1
            )
            seeds.extend(qs[np.argsort(dist, kind="stable")[:k]])
        toward = home.copy()
        toward[0] = np.clip(
            np.arctan2(target.position[1], target.position[0]), self.lower[0], self.upper[0]
        )
        seeds = [*seeds, toward, home.copy()][:n]
        while len(seeds) < n and rng is not None:
            seeds.append(home + rng.normal(0.0, self.config.seed_spread_rad, size=7))
        return seeds

    def solve(
        self,
        target: Pose,
        q_seed: ArrayLike,
        rng: np.random.Generator | None = None,
        restarts: int | None = None,
        closest_to: ArrayLike | None = None,
    ) -> IKSolution:
        """Joint angles that put the TCP on ``target``, from the seeds of :meth:`seeds`.

        Without ``closest_to`` the first acceptable solution is returned. With it, every restart
        runs and the acceptable solution nearest to ``closest_to`` wins (largest joint change,
        then summed squares: the shortest joint-space move), which avoids folded or turned-around
        branches that a first hit may land in; the other distinct acceptable solutions (more
        than 0.1 rad apart) are kept in ``alternatives``, nearest first. With no acceptable
        solution, the one with the smallest error is returned with ``ok=False``.
        """
        cfg = self.config
        n = cfg.restarts if restarts is None else restarts
        home = self.panda.home_arm_q
        ref = None if closest_to is None else np.asarray(closest_to, dtype=float)
        m = cfg.joint_limit_margin_rad
        best: IKSolution | None = None
        accepted: list[tuple[float, IKSolution]] = []
        iterations = blocked = tried = 0
        for seed in self.seeds(target, q_seed, n, rng):
            q, ep, er, it = self._descend(target, seed, home)
            iterations += it
            tried += 1
            reason = ""
            clear = float("inf")
            if ep > cfg.position_tolerance_m or er > cfg.orientation_tolerance_deg:
                reason = f"pose error {ep * 1000:.1f} mm / {er:.1f} deg after {it} iterations"
            elif np.any(q < self.lower + 0.5 * m) or np.any(q > self.upper - 0.5 * m):
                j = int(np.argmax(np.maximum(self.lower - q, q - self.upper)))
                reason = f"joint {j + 1} at its limit ({q[j]:.2f} rad)"
            elif len(self.obstacle_geoms):
                margin, geom, clear = self.clearance(q)
                if margin < 0:
                    body = self.model.body(self.model.geom_bodyid[geom]).name
                    reason = f"{body} {clear * 1000:.1f} mm from the table or bin"
                    blocked += int(self.model.geom_bodyid[geom] in self._rigid)
            sol = IKSolution(q, not reason, ep, er, clear, tried, iterations, reason)
            if sol.ok:
                if ref is None:
                    return sol
                dq = np.abs(q - ref)
                accepted.append((float(dq.max() + 0.1 * np.sqrt(dq @ dq)), sol))
            elif best is None or (ep, er) < (best.position_error_m, best.orientation_error_deg):
                best = sol
            if not accepted and blocked >= cfg.max_blocked_restarts:
                # The pose is reached but the hand (or link7, rigid with it) is in the table or
                # bin: the target fixes where they are, so other arm postures cannot help.
                break
        if accepted:
            accepted.sort(key=lambda a: a[0])
            chosen = accepted[0][1]
            chosen.restarts, chosen.iterations = tried, iterations
            # Other distinct solutions (other branches), nearest first.
            for _, other in accepted[1:]:
                if all(np.abs(other.q - a).max() > 0.1 for a in [chosen.q, *chosen.alternatives]):
                    chosen.alternatives.append(other.q)
            return chosen
        assert best is not None
        best.restarts, best.iterations = tried, iterations
        best.reason = f"unreachable after {tried} restart(s): {best.reason}"
        return best

    def solve_path(self, poses: Sequence[Pose], q_start: ArrayLike) -> PathSolution:
        """Waypoints for ``poses`` (a line, say), each seeded from the previous solution without
        random restarts so the arm stays on one branch; fails on an unreachable waypoint or a
        joint jump above ``max_waypoint_jump_rad``."""
        q_prev = np.asarray(q_start, dtype=float)
        out, sols = [], []
        for i, pose in enumerate(poses):
            sol = self.solve(pose, q_prev, rng=None, restarts=1)
            sols.append(sol)
            if not sol.ok:
                return PathSolution(np.array(out), False, f"waypoint {i}: {sol.reason}", sols)
            jump = float(np.max(np.abs(sol.q - q_prev)))
            if i > 0 and jump > self.config.max_waypoint_jump_rad:
                return PathSolution(
                    np.array(out),
                    False,
                    f"waypoint {i}: joint jump {jump:.2f} rad (a branch change)",
                    sols,
                )
            out.append(sol.q)
            q_prev = sol.q
        return PathSolution(np.array(out), True, "", sols)

    def solve_line(
        self, start: Pose, end_position: ArrayLike, n_segments: int, q_start: ArrayLike
    ) -> PathSolution:
        """Waypoints along a straight TCP line (constant orientation) from ``start``, the first
        seeded with ``q_start``. A joint jump between waypoints above ``max_waypoint_jump_rad``
        is first taken for too coarse a sampling (near a joint limit the joints may move fast
        along the line): the line is re-solved with twice the segments, up to
        ``line_refinements`` times; a jump that does not shrink is a branch change."""
        n = n_segments
        for _ in range(self.config.line_refinements + 1):
            path = self.solve_path(line_poses(start, end_position, n), q_start)
            if path.ok or "joint jump" not in path.reason:
                return path
            n *= 2
        return path
