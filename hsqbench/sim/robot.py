"""The Franka Emika Panda from MuJoCo Menagerie, with a hand that grasps like the real one.

The model is Menagerie's ``franka_emika_panda`` entry point ``panda`` (arm plus Franka Hand),
loaded as an :class:`mujoco.MjSpec`. :func:`apply_modifications` is the one place that changes
it; the values live in ``configs/robot.yaml``. The changes, each with its reason:

1. Gripper actuator. Menagerie's ``actuator8`` is a position servo on the finger tendon with a
   stiffness of 100 N/m per metre of finger travel: closed on a 6 cm object it squeezes with
   about 1.5 N per finger, so a 1 kg bottle slides out. The real Franka Hand grasps with 70 N
   continuous (140 N peak). It is replaced by ``gripper``, a force-limited position servo on the
   same tendon. Per finger: ``f = clip(k (w_t / 2 - q), -f_max, f_max)``, where ``q`` is the
   finger's travel from the centre and ``w_t`` a width target that follows the commanded width
   through a first-order filter (time constant ``tau``), so free fingers move at about
   ``(w_cmd - w) / (2 tau)`` instead of jumping. The command to close is a width below zero, so
   on anything wider than ``2 f_max / k + close_width`` the force limit, not the stiffness, sets
   the squeeze: the hand behaves like the real one's ``grasp`` (close at a moderate speed,
   then hold a set force). Opening is the same servo with a positive width. The finger joints'
   damping becomes ``c`` (Menagerie: 1 N s/m), about critical for the servo. Limiting the speed
   with a large damping instead does not work in MuJoCo: damping is integrated implicitly,
   after the contact solver, and with 1400 N s/m the pads ring on the object by +-35 N.
2. Finger pads. The five box pads on each fingertip get rubber-like friction, torsional and
   rolling friction (``condim`` 6: a grasped object resists spinning about the closing axis and
   rocking about an axis in the pad plane, as it does on the real pads' pressed contact
   patch, which a point contact cannot represent) and a stiffer contact so 70 N does not sink
   the pads into the object.
3. TCP site ``tcp``: the grasp centre between the fingertip pads (the closing point P_G of the
   paper). Its frame: x = closing axis (direction of finger motion, from the right finger
   toward the left finger), z = approach axis (from the palm toward the fingertips),
   y = z × x. A planner grasp with rotation columns (closing axis, third axis, approach axis)
   and centre P_G is reached by putting this site's frame on it.
4. Gravity compensation of the arm links (``gravcomp``): the real Panda's controller cancels
   gravity in its torque loop, so its joint servos track without a load-dependent sag. Without
   it, Menagerie's servos sag a few millimetres at the fingertips (see ``configs/robot.yaml``).

Unchanged: geometry, masses, joint limits, armature, arm joint damping, the finger equality, and the
arm actuators ``actuator1..7`` (position servos with Menagerie's gains, control and force
ranges). The arm is commanded by joint targets in radians through those actuators.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from hsqbench.config import load_config
from hsqbench.sim.physics import ContactConfig

ARM_JOINTS = tuple(f"joint{i}" for i in range(1, 8))
ARM_ACTUATORS = tuple(f"actuator{i}" for i in range(1, 8))
FINGER_JOINTS = ("finger_joint1", "finger_joint2")
FINGER_BODIES = ("left_finger", "right_finger")
ARM_BODIES = ("link1", "link2", "link3", "link4", "link5", "link6", "link7", "hand")
MENAGERIE_GRIPPER = "actuator8"
GRIPPER = "gripper"
GRIPPER_TENDON = "split"
TCP_SITE = "tcp"
HAND_BODY = "hand"
BASE_BODY = "link0"
HOME_NUMERIC = "home_arm_qpos"
PAD_CLASS_PREFIX = "fingertip_pad_collision"


@dataclass(frozen=True)
class GripperConfig:
    """Force-limited position servo of the hand (see modification 1).

    Attributes:
        max_force_per_finger_n: force limit of each finger, N.
        stiffness_n_per_m: per-finger position gain, N per metre of finger travel.
        damping_ns_per_m: viscous damping of each finger joint, N s/m.
        target_time_constant_s: time constant of the filter from commanded to target width, s.
        close_width_m: width commanded to close (below zero, so the force limit sets the squeeze).
        open_width_m: width commanded to open fully.
    """

    max_force_per_finger_n: float = 70.0
    stiffness_n_per_m: float = 10000.0
    damping_ns_per_m: float = 60.0
    target_time_constant_s: float = 0.5
    close_width_m: float = -0.02
    open_width_m: float = 0.08

    def __post_init__(self) -> None:
        for name in (
            "max_force_per_finger_n",
            "stiffness_n_per_m",
            "damping_ns_per_m",
            "target_time_constant_s",
        ):
            if getattr(self, name) <= 0:
                raise ValueError(f"gripper.{name} must be positive, got {getattr(self, name)}")


@dataclass(frozen=True)
class RobotConfig:
    """Which Menagerie model to load and how to modify it.

    Attributes:
        menagerie_model, entry_point: ``mujoco_menagerie.get(model).xml(entry_point)``.
        prefix: name prefix of every robot element in a composed scene.
        realistic_hand: apply modifications 1 and 2 (False keeps Menagerie's hand, for tests).
        gripper: the replacement gripper actuator.
        pads: contact parameters of the fingertip pads.
        tcp_offset_m: distance of the TCP site from the hand frame along the approach axis.
        gravity_compensation: apply modification 4.
    """

    menagerie_model: str = "franka_emika_panda"
    entry_point: str = "panda"
    prefix: str = "panda/"
    realistic_hand: bool = True
    gripper: GripperConfig = field(default_factory=GripperConfig)
    pads: ContactConfig = field(
        default_factory=lambda: ContactConfig(
            friction=(1.0, 0.0065, 0.002),
            condim=6,
            solref=(0.004, 1.0),
            solimp=(0.95, 0.99, 0.001, 0.5, 2.0),
        )
    )
    tcp_offset_m: float = 0.1034
    gravity_compensation: bool = True


def load_robot_config(path: str | Path | None = "robot") -> RobotConfig:
    """Load ``configs/robot.yaml`` (or another file); ``None`` gives the built-in defaults."""
    return load_config(RobotConfig, path)


def menagerie_path(cfg: RobotConfig) -> Path:
    """Path of the Menagerie XML (``MENAGERIE_ROOT`` is honoured by ``mujoco_menagerie``)."""
    import mujoco_menagerie as mm

    try:
        path = Path(mm.get(cfg.menagerie_model).xml(cfg.entry_point))
    except Exception as exc:  # the package raises its own types for unknown names and roots
        raise FileNotFoundError(
            f"cannot locate Menagerie model {cfg.menagerie_model!r} entry {cfg.entry_point!r}: "
            f"{exc}. Set MENAGERIE_ROOT to a MuJoCo Menagerie checkout."
        ) from exc
    if not path.exists():
        raise FileNotFoundError(
            f"{path} does not exist; set MENAGERIE_ROOT to a Menagerie checkout"
        )
    return path


def load_panda_spec(cfg: RobotConfig | None = None) -> mujoco.MjSpec:
    """The Menagerie Panda as a spec, modified by :func:`apply_modifications`.

    Menagerie's keyframe is removed (a composed scene has more degrees of freedom) and its arm
    configuration is kept as the numeric ``home_arm_qpos``; its light is removed (the scene
    lights itself).
    """
    cfg = cfg or load_robot_config()
    spec = mujoco.MjSpec.from_file(str(menagerie_path(cfg)))
    home = spec.key("home")
    spec.add_numeric(name=HOME_NUMERIC, data=list(home.qpos)[: len(ARM_JOINTS)])
    for key in list(spec.keys):
        spec.delete(key)
    for light in list(spec.lights):
        spec.delete(light)
    apply_modifications(spec, cfg)
    return spec


def apply_modifications(spec: mujoco.MjSpec, cfg: RobotConfig) -> None:
    """Apply the documented changes (module docstring) to an unprefixed Menagerie Panda spec."""
    if cfg.realistic_hand:
        _replace_gripper_actuator(spec, cfg.gripper)
        for geom in spec.geoms:
            if geom.classname.name.startswith(PAD_CLASS_PREFIX):
                cfg.pads.apply(geom)
    hand = spec.body(HAND_BODY)
    # Rz(+90 deg): site x = hand y (finger motion), site y = -hand x, site z = hand z (approach).
    half = np.sqrt(0.5)
    hand.add_site(
        name=TCP_SITE,
        pos=[0.0, 0.0, cfg.tcp_offset_m],
        quat=[half, 0.0, 0.0, half],
        size=[0.005, 0.005, 0.005],
        rgba=[1.0, 0.2, 0.2, 1.0],
        group=4,
    )
    if cfg.gravity_compensation:
        for name in ARM_BODIES:
            spec.body(name).gravcomp = 1.0


def _replace_gripper_actuator(spec: mujoco.MjSpec, g: GripperConfig) -> None:
    """Modification 1, written on the tendon ``split`` whose length is the mean finger travel.

    The tendon's length L equals each finger's travel q (the fingers are coupled), and a tendon
    force F puts F/2 on each finger. So per-finger (k, f_max) become tendon values (2k, 2 f_max),
    and with a control u in width units (L* = u / 2) the servo F = 2k (u/2 - L) is gain k on u
    and bias (0, -2k, 0). The damping c goes on the finger joints.
    """
    spec.delete(spec.actuator(MENAGERIE_GRIPPER))
    spec.add_actuator(
        name=GRIPPER,
        trntype=mujoco.mjtTrn.mjTRN_TENDON,
        target=GRIPPER_TENDON,
        gaintype=mujoco.mjtGain.mjGAIN_FIXED,
        gainprm=[g.stiffness_n_per_m] + [0.0] * 9,
        biastype=mujoco.mjtBias.mjBIAS_AFFINE,
        biasprm=[0.0, -2.0 * g.stiffness_n_per_m, 0.0] + [0.0] * 7,
        dyntype=mujoco.mjtDyn.mjDYN_FILTEREXACT,
        dynprm=[g.target_time_constant_s] + [0.0] * 9,
        ctrlrange=[min(g.close_width_m, 0.0), g.open_width_m],
        forcerange=[-2.0 * g.max_force_per_finger_n, 2.0 * g.max_force_per_finger_n],
    )
    for name in FINGER_JOINTS:
        spec.joint(name).damping = [g.damping_ns_per_m, 0.0, 0.0]  # linear term only


class Hand:
    """Handles into a compiled model that contains the Franka Hand (ids resolved once).

    Works for the full Panda and for the hand alone (the hold-test rig).

    Args:
        model: a compiled model containing the hand.
        prefix: the robot's name prefix in that model.
    """

    def __init__(self, model: mujoco.MjModel, prefix: str = "panda/") -> None:
        self.model = model
        self.prefix = prefix
        p = prefix
        self.finger_joint_names = tuple(p + n for n in FINGER_JOINTS)
        fingers = [model.joint(n) for n in self.finger_joint_names]
        self.finger_qpos_adr = np.array([j.qposadr[0] for j in fingers])
        self.finger_dof_adr = np.array([j.dofadr[0] for j in fingers])
        try:
            self.gripper_actuator_id = model.actuator(p + GRIPPER).id
        except KeyError:
            self.gripper_actuator_id = model.actuator(p + MENAGERIE_GRIPPER).id
        self.gripper_actuator_name = model.actuator(self.gripper_actuator_id).name
        self._gripper_act_adr = int(model.actuator_actadr[self.gripper_actuator_id])
        self.hand_body_id = model.body(p + HAND_BODY).id
        self.finger_body_ids = np.array([model.body(p + n).id for n in FINGER_BODIES])
        self.tcp_site_id = model.site(p + TCP_SITE).id
        root = model.body_rootid[self.hand_body_id]
        # Bodies of the robot's kinematic tree: contacts with them are not contacts with objects.
        self.body_ids = np.flatnonzero(model.body_rootid == root)

    # ---- hand ------------------------------------------------------------------------------
    def max_width(self) -> float:
        """Largest opening width of the hand, metres (twice the finger joint range)."""
        jid = self.model.joint(self.finger_joint_names[0]).id
        return float(2.0 * self.model.jnt_range[jid, 1])

    def gripper_width(self, data: mujoco.MjData) -> float:
        """Current opening width between the fingers, metres (sum of the two finger travels)."""
        return float(data.qpos[self.finger_qpos_adr].sum())

    def _ctrl_for_width(self, width_m: float) -> float:
        # Affine servo F = g u + b1 L (+ b2 dL): force-free at L = -g u / b1, with L = width / 2.
        a = self.gripper_actuator_id
        g = self.model.actuator_gainprm[a, 0]
        b1 = self.model.actuator_biasprm[a, 1]
        u = -b1 * (width_m / 2.0) / g
        lo, hi = self.model.actuator_ctrlrange[a]
        return float(np.clip(u, lo, hi))

    def _close_command(self) -> float:
        return float(self.model.actuator_ctrlrange[self.gripper_actuator_id, 0])

    def set_gripper(self, data: mujoco.MjData, width_m: float) -> None:
        """Command an opening width in metres (0.08 is fully open). Below the object's width the
        hand squeezes with its force limit; use :meth:`close_gripper` to grasp."""
        if not np.isfinite(width_m):
            raise ValueError(f"gripper width must be finite, got {width_m}")
        data.ctrl[self.gripper_actuator_id] = self._ctrl_for_width(width_m)

    def sync_gripper_target(self, data: mujoco.MjData) -> None:
        """Make the filtered width target equal the command now (after writing ``qpos`` by hand,
        so the fingers do not move toward an old target)."""
        if self._gripper_act_adr >= 0:
            data.act[self._gripper_act_adr] = data.ctrl[self.gripper_actuator_id]

    def open_gripper(self, data: mujoco.MjData) -> None:
        data.ctrl[self.gripper_actuator_id] = self.model.actuator_ctrlrange[
            self.gripper_actuator_id, 1
        ]

    def close_gripper(self, data: mujoco.MjData) -> None:
        """Close with the full grasp force (the command below zero width)."""
        data.ctrl[self.gripper_actuator_id] = self._close_command()

    def squeeze_force(self, data: mujoco.MjData) -> float:
        """Closing force the gripper actuator applies on each finger now, N (positive closes).
        It reaches ``max_force_per_finger_n`` once a grasp has settled."""
        return float(-0.5 * data.actuator_force[self.gripper_actuator_id])

    def finger_forces(self, data: mujoco.MjData, body_id: int | None = None) -> np.ndarray:
        """Normal contact force (N) on the (left, right) finger from ``body_id`` (any non-robot
        body when ``None``), summed over contacts."""
        out = np.zeros(2)
        ncon = data.ncon
        if ncon == 0:
            return out
        geom_body = self.model.geom_bodyid[data.contact.geom[:ncon]]
        wrench = np.zeros(6)
        for side, fid in enumerate(self.finger_body_ids):
            on_finger = geom_body == fid
            other = np.where(on_finger[:, 0], geom_body[:, 1], geom_body[:, 0])
            hit = on_finger.any(axis=1)
            if body_id is None:
                hit &= ~np.isin(other, self.body_ids)
            else:
                hit &= other == body_id
            for i in np.flatnonzero(hit):
                mujoco.mj_contactForce(self.model, data, int(i), wrench)
                out[side] += wrench[0]
        return out

    def tcp_pose(self, data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
        """World position (3,) and rotation (3, 3) of the TCP site (columns: closing, y, approach)."""
        return (
            data.site_xpos[self.tcp_site_id].copy(),
            data.site_xmat[self.tcp_site_id].reshape(3, 3).copy(),
        )


class Panda(Hand):
    """Handles into a compiled model that contains the whole Panda: arm plus :class:`Hand`."""

    def __init__(self, model: mujoco.MjModel, prefix: str = "panda/") -> None:
        super().__init__(model, prefix)
        p = prefix
        self.arm_joint_names = tuple(p + n for n in ARM_JOINTS)
        self.arm_actuator_names = tuple(p + n for n in ARM_ACTUATORS)
        arm_j = [model.joint(n) for n in self.arm_joint_names]
        self.arm_qpos_adr = np.array([j.qposadr[0] for j in arm_j])
        self.arm_dof_adr = np.array([j.dofadr[0] for j in arm_j])
        self.arm_actuator_ids = np.array([model.actuator(n).id for n in self.arm_actuator_names])
        self.base_body_id = model.body(p + BASE_BODY).id
        self.home_arm_q = np.array(model.numeric(p + HOME_NUMERIC).data, dtype=float)
        self.arm_ctrl_range = model.actuator_ctrlrange[self.arm_actuator_ids].copy()

    # ---- arm -------------------------------------------------------------------------------
    def arm_q(self, data: mujoco.MjData) -> np.ndarray:
        """Current arm joint angles (7,), radians."""
        return data.qpos[self.arm_qpos_adr].copy()

    def set_arm_targets(self, data: mujoco.MjData, q: np.ndarray) -> None:
        """Command arm joint targets (7,) in radians; raises if outside the actuator ranges."""
        q = np.asarray(q, dtype=float)
        if q.shape != (7,) or not np.all(np.isfinite(q)):
            raise ValueError(f"arm targets must be 7 finite angles in radians, got {q!r}")
        lo, hi = self.arm_ctrl_range.T
        if np.any(q < lo - 1e-9) or np.any(q > hi + 1e-9):
            bad = np.flatnonzero((q < lo - 1e-9) | (q > hi + 1e-9))
            raise ValueError(
                f"arm targets outside the joint ranges for joints {[int(i) + 1 for i in bad]}: "
                f"{q[bad]} not in {self.arm_ctrl_range[bad].tolist()}"
            )
        data.ctrl[self.arm_actuator_ids] = q

    def reset_home(self, data: mujoco.MjData, open_gripper: bool = True) -> None:
        """Put the arm at Menagerie's ``home`` configuration, at rest, with matching commands."""
        data.qpos[self.arm_qpos_adr] = self.home_arm_q
        data.qvel[self.arm_dof_adr] = 0.0
        data.ctrl[self.arm_actuator_ids] = self.home_arm_q
        width = self.max_width() if open_gripper else 0.0
        data.qpos[self.finger_qpos_adr] = width / 2.0
        data.qvel[self.finger_dof_adr] = 0.0
        if open_gripper:
            self.set_gripper(data, width)
        else:
            self.close_gripper(data)
        self.sync_gripper_target(data)
