"""The trial environment: a built scene with the robot handles, IK, probe, sensor and the
bookkeeping of objects removed from it."""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.ik import ArmIK
from hsqbench.sim.judge import Box, SceneProbe
from hsqbench.sim.motion import Stepper
from hsqbench.sim.objects import ObjectLike, resolve_object
from hsqbench.sim.recorder import NullRecorder, Recorder
from hsqbench.sim.robot import Panda
from hsqbench.sim.surface_sensor import SurfaceSensor
from hsqbench.sim.trial.config import TrialConfig
from hsqbench.sim.trial.geometry import lift_height
from hsqbench.sim.trial.presentation import CACHE, FirstLook, Look, Presentation, copied

#: Independent random streams drawn from a trial's seed.
STREAMS = ("perception_calibration", "perception_noise", "ik", "planner", "oracle")
#: The streams a look draws from (:meth:`TrialEnv.look`), and nothing else does.
LOOK_STREAMS = ("perception_calibration", "perception_noise", "oracle")


def trial_rngs(seed: int) -> dict[str, np.random.Generator]:
    """The trial's random streams (:data:`STREAMS`), each from its own ``SeedSequence`` child."""
    streams = np.random.SeedSequence(seed).spawn(len(STREAMS))
    return {n: np.random.default_rng(s) for n, s in zip(STREAMS, streams, strict=True)}


class TrialEnv:
    """A built scene with everything an attempt needs (robot handles, IK, probe, sensor).

    Build with :meth:`build`; close with :meth:`close` (frees the cameras' renderers unless a
    kept :class:`~hsqbench.sim.trial.presentation.Presentation` owns them).
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        info: Any,
        assets: dict[str, ObjectLike],
        config: TrialConfig,
        seed: int,
        recorder: Recorder,
        presentation: Presentation | None = None,
    ) -> None:
        self.model, self.data, self.info = model, data, info
        self.assets = assets
        self.config = config
        self.seed = seed
        self.recorder = recorder
        self.rngs = trial_rngs(seed)
        self.panda = Panda(model, info.robot_prefix)
        obstacles = np.array([info.table_geom_id, *info.bin_geom_ids], dtype=int)
        self.ik = ArmIK(model, self.panda, config.ik, obstacles)
        self.ik.sync(data, self.panda.max_width())
        #: (lo, hi) bounding box of the open hand in the TCP frame, metres.
        self.hand_box = self.ik.hand_extent()
        self.bin_box = Box(np.asarray(info.bin_min, float), np.asarray(info.bin_max, float))
        # Where an object still takes part: over the region the cameras keep (the workspace and
        # the crop's margin) and not fallen below the table top. Outside it no planner can see
        # it, so a packed round takes it out (not cleared) rather than plan on an empty cloud.
        margin = self.crop_margin_m()
        self.workspace_box = Box(
            np.array(
                [
                    *(info.workspace_min[:2] - margin),
                    info.table_top_z - config.judge.off_table_below_m,
                ]
            ),
            np.array([*(info.workspace_max[:2] + margin), info.table_top_z + 2.0]),
        )
        self.probe = SceneProbe(
            model, self.panda, info.object_body_ids, obstacles, self.bin_box, self.workspace_box
        )
        self.stepper = Stepper(model, data, self.panda, config.motion, recorder)
        self.removed: set[str] = set()
        self.presentation = presentation
        self._sensor: Any = None if presentation is None else presentation.sensor
        self._oracle: Any = None
        self._looked = False
        #: Wall seconds this trial spent building its scene (a kept presentation: resetting it).
        self.build_s = 0.0

    @classmethod
    def build(
        cls,
        kind: str,
        objects: Sequence[str | ObjectLike] | str | ObjectLike | None,
        seed: int,
        config: TrialConfig,
        recorder: Recorder | None = None,
    ) -> TrialEnv:
        if isinstance(objects, str) or (objects is not None and not isinstance(objects, Sequence)):
            objects = [objects]
        t0 = time.perf_counter()
        rec = recorder if recorder is not None else NullRecorder()
        key = None if rec.enabled else CACHE.key(kind, objects, seed)
        kept = CACHE.get(key, config)
        if kept is not None:
            data = kept.fresh_data()
            env = cls(kept.model, data, kept.info, kept.assets, config, seed, rec, kept)
            env.build_s = time.perf_counter() - t0
            return env
        from hsqbench.sim.scene import build_scene

        resolved = None if objects is None else [resolve_object(o) for o in objects]
        model, data, info = build_scene(
            kind,
            resolved,
            seed,
            scene_config=config.scene,
            robot_config=config.robot,
            physics_config=config.physics,
        )
        if resolved is None:
            resolved = [resolve_object(n) for n in info.objects]
        assets = {a.name: a for a in resolved}
        if key is not None:
            kept = Presentation(key, config, model, info, assets)
            CACHE.put(kept)
        env = cls(model, data, info, assets, config, seed, rec, kept)
        if rec.enabled:
            rec.on_scene(model, data, info)
        env.build_s = time.perf_counter() - t0
        return env

    def close(self) -> None:
        owned = self.presentation is None or self.presentation.sensor is not self._sensor
        if owned and self._sensor is not None and hasattr(self._sensor, "close"):
            self._sensor.close()
        self._sensor = None

    def __enter__(self) -> TrialEnv:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- sensing -------------------------------------------------------------------------------
    def crop_margin_m(self) -> float:
        """How far beyond the workspace the sensor in use keeps points, metres."""
        cfg = self.config
        if cfg.sensor == "surface":
            return cfg.surface.workspace_margin_m
        return cfg.perception.crop.workspace_margin_m

    def _make_sensor(self) -> Any:
        cfg = self.config
        if cfg.sensor == "surface":
            return SurfaceSensor(
                self.assets,
                self.info.object_body_ids,
                [self.model.camera(c.name).id for c in self.info.depth_cameras],
                self.info.workspace_min,
                self.info.workspace_max,
                self.info.table_top_z,
                cfg.surface,
            )
        from hsqbench.sim.perception import Perception

        return Perception.from_scene(
            self.model, self.info, rng=self.rngs["perception_calibration"], config=cfg.perception
        )

    def look(self) -> Look:
        """Perceive, then the true hulls and the graspability check (:class:`Look`). The first
        look of a kept presentation is made once and handed to every later trial of it
        (:mod:`hsqbench.sim.trial.presentation`)."""
        kept, first = self.presentation, not self._looked
        self._looked = True
        if first and kept is not None and kept.first_look is not None:
            # The data calls and draws that making the look makes, then the look itself.
            mujoco.mj_forward(self.model, self.data)
            mujoco.mj_kinematics(self.model, self.data)
            for name, state in kept.first_look.states.items():
                self.rngs[name].bit_generator.state = state
            return copied(kept.first_look.look)
        t0 = time.perf_counter()
        obs = self.observe()
        seconds = time.perf_counter() - t0
        truth = self.truth()
        look = Look(obs, seconds, truth, self.graspable_objects(truth))
        if first and kept is not None:
            states = {n: self.rngs[n].bit_generator.state for n in LOOK_STREAMS}
            kept.first_look = FirstLook(copied(look), states)
        return look

    def observe(self) -> Any:
        """The perceived cloud now (``points`` (N, 3), ``camera_positions`` (C, 3))."""
        if self._sensor is None:
            self._sensor = self._make_sensor()
            if self.presentation is not None:
                self.presentation.sensor = self._sensor
        if isinstance(self._sensor, SurfaceSensor):
            self._sensor.objects = {n: a for n, a in self.assets.items() if n not in self.removed}
        mujoco.mj_forward(self.model, self.data)
        return self._sensor.observe(self.data, self.rngs["perception_noise"])

    # ---- truth (the oracle's; never a perceiving planner's) ------------------------------------
    def truth(self) -> Any:
        """The true hulls of the objects on the table now (:mod:`hsqbench.sim.scene_truth`)."""
        from hsqbench.sim.scene_truth import scene_truth

        names = self.objects_on_table()
        seed = int(self.rngs["oracle"].integers(2**31))
        return scene_truth(
            self.model,
            self.data,
            self.info.object_geom_ids,
            names,
            self.info.support_plane,
            seed,
            self.panda,
        )

    def graspable_objects(self, truth: Any) -> list[str] | None:
        """Objects on which the oracle finds a feasible grasp (None: the check is off)."""
        if self.config.graspability is None:
            return None
        from hsqbench.planner.oracle import OraclePlanner, feasible_grasps

        if self._oracle is None:
            self._oracle = OraclePlanner(self.config.graspability)
        counts = feasible_grasps(truth, self._oracle.gripper, self._oracle.config, truth.seed)
        return [n for n, c in counts.items() if c > 0]

    def object_pose(self, name: str) -> tuple[float, ...]:
        """(x, y, z, qw, qx, qy, qz) of an object now."""
        body = self.info.object_body_ids[name]
        adr = self.model.jnt_qposadr[self.model.body_jntadr[body]]
        return tuple(float(x) for x in self.data.qpos[adr : adr + 7])

    # ---- geometry of the scene ---------------------------------------------------------------
    def lift_height(self) -> float:
        """TCP rise of the lift (:func:`~hsqbench.sim.trial.geometry.lift_height`)."""
        ex = self.config.execution
        return lift_height(
            ex.lift_height_m, self.bin_box.hi[2], ex.carry_clearance_m, self.info.table_top_z
        )

    def bin_centre_xy(self) -> NDArray[np.float64]:
        return 0.5 * (self.bin_box.lo[:2] + self.bin_box.hi[:2])

    # ---- scene bookkeeping ---------------------------------------------------------------------
    def objects_on_table(self) -> list[str]:
        """Objects not removed, on the table in the workspace (not in the bin, not fallen off,
        not pushed out of the cameras' view)."""
        return [
            n
            for n in self.info.objects
            if n not in self.removed
            and self.probe.in_workspace(self.data, n)
            and not self.probe.in_bin(self.data, n)
        ]

    def remove(self, name: str) -> None:
        """Take an object out of the scene: parked far away, floating (gravity compensated),
        with its collisions off, so it never touches anything again."""
        k = self.info.objects.index(name)
        body = self.info.object_body_ids[name]
        self.model.body_gravcomp[body] = 1.0
        geoms = self.model.geom_bodyid == body
        self.model.geom_contype[geoms] = 0
        self.model.geom_conaffinity[geoms] = 0
        park_x, park_y = self.config.execution.park_xy_m
        self.probe.set_free_pose(self.data, name, np.array([park_x + k, park_y, 1.0]))
        self.removed.add(name)
        mujoco.mj_forward(self.model, self.data)
