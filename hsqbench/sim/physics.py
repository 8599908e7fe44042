"""MuJoCo solver options and contact parameters: ``configs/physics.yaml`` applied to a spec.

One place sets how the simulation integrates and how contacts behave, so the scene, the hold
test and the trial runner all run the same physics. The reasons for each value are in the YAML.

Contact model reminders (MuJoCo): a contact's friction is the element-wise maximum of the two
geoms' ``friction`` (sliding, torsional in metres, rolling in metres), its ``condim`` the larger
of the two; ``solref = (timeconst_s, dampratio)`` sets how stiff and damped the soft constraint
is, ``solimp`` how much of the constraint force is applied as a function of penetration.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import mujoco

from hsqbench.config import load_config


@dataclass(frozen=True)
class ContactConfig:
    """Contact parameters of a class of geoms.

    Attributes:
        friction: (sliding, torsional_m, rolling_m) coefficients.
        condim: 1 (frictionless), 3 (sliding), 4 (+torsional) or 6 (+rolling).
        solref: (time constant in seconds, damping ratio).
        solimp: (dmin, dmax, width_m, midpoint, power).
    """

    friction: tuple[float, float, float] = (0.6, 0.005, 0.0001)
    condim: int = 3
    solref: tuple[float, float] = (0.01, 1.0)
    solimp: tuple[float, float, float, float, float] = (0.95, 0.99, 0.001, 0.5, 2.0)

    def __post_init__(self) -> None:
        if self.condim not in (1, 3, 4, 6):
            raise ValueError(f"condim must be 1, 3, 4 or 6, got {self.condim}")
        if min(self.friction) < 0:
            raise ValueError(f"friction must be non-negative, got {self.friction}")

    def apply(self, geom: mujoco.MjsGeom) -> None:
        """Set these contact parameters on a spec geom."""
        geom.friction = list(self.friction)
        geom.condim = self.condim
        geom.solref = list(self.solref)
        geom.solimp = list(self.solimp)


@dataclass(frozen=True)
class PhysicsConfig:
    """Global solver options plus the contact classes used by the scene.

    Attributes:
        timestep_s: integration step.
        integrator: MuJoCo integrator name.
        cone: friction cone type.
        impratio: ratio of frictional to normal constraint impedance (elliptic cones).
        iterations, ls_iterations: main solver and line-search iteration limits.
        tolerance: main solver tolerance.
        noslip_iterations: post-solve iterations that remove residual slip (0 = off).
        open_hand_noslip_iterations: the same once the hand has opened to release an object,
            until it is home (:func:`hsqbench.sim.trial.release.open_hand_contacts`).
        objects: contact parameters of object collision hulls.
        table: contact parameters of the table top and the bin.
        settle_time_s: simulated time given to a new scene to come to rest.
        settle_speed_mps: largest body speed (m/s, and rad/s for spins) that counts as at rest.
        rest_checks: after ``settle_time_s``, how many times a scene still moving has its
            objects stopped and let go (:func:`hsqbench.sim.scene.world.come_to_rest`).
        rest_check_s: simulated time each let-go runs before the speed is checked again.
        object_mass_scale: every object's mass and inertia times this (1: the library's
            masses); for sweeps of how heavy the objects are.
    """

    timestep_s: float = 0.002
    integrator: Literal["euler", "rk4", "implicit", "implicitfast"] = "implicitfast"
    cone: Literal["pyramidal", "elliptic"] = "elliptic"
    impratio: float = 10.0
    iterations: int = 100
    ls_iterations: int = 50
    tolerance: float = 1e-8
    noslip_iterations: int = 10
    open_hand_noslip_iterations: int = 0
    # The defaults are configs/physics.yaml's (tests/test_config_defaults.py): the table's
    # contact is ContactConfig's; objects grip better and twist less (friction 0.8, condim 4).
    objects: ContactConfig = field(
        default_factory=lambda: ContactConfig(friction=(0.8, 0.005, 0.0001), condim=4)
    )
    table: ContactConfig = field(default_factory=ContactConfig)
    settle_time_s: float = 1.0
    settle_speed_mps: float = 0.005
    rest_checks: int = 50
    rest_check_s: float = 0.1
    object_mass_scale: float = 1.0

    def __post_init__(self) -> None:
        if self.timestep_s <= 0:
            raise ValueError(f"timestep_s must be positive, got {self.timestep_s}")
        if self.impratio < 1:
            raise ValueError(f"impratio must be >= 1, got {self.impratio}")
        if self.rest_checks < 0 or not self.rest_check_s > 0:
            raise ValueError(
                f"rest_checks must be >= 0 and rest_check_s > 0, got {self.rest_checks} and "
                f"{self.rest_check_s}"
            )
        if not self.object_mass_scale > 0:
            raise ValueError(f"object_mass_scale must be positive, got {self.object_mass_scale}")


_INTEGRATORS = {
    "euler": mujoco.mjtIntegrator.mjINT_EULER,
    "rk4": mujoco.mjtIntegrator.mjINT_RK4,
    "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
    "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
}
_CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}


def load_physics_config(path: str | Path | None = "physics") -> PhysicsConfig:
    """Load ``configs/physics.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(PhysicsConfig, path)


def apply_physics(spec: mujoco.MjSpec, cfg: PhysicsConfig) -> None:
    """Write the global solver options of ``cfg`` into ``spec.option``."""
    opt = spec.option
    opt.timestep = cfg.timestep_s
    opt.integrator = _INTEGRATORS[cfg.integrator]
    opt.cone = _CONES[cfg.cone]
    opt.impratio = cfg.impratio
    opt.iterations = cfg.iterations
    opt.ls_iterations = cfg.ls_iterations
    opt.tolerance = cfg.tolerance
    opt.noslip_iterations = cfg.noslip_iterations
