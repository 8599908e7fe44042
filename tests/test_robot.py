"""The Panda as modified in hsqbench.sim.robot: what changed, what did not, and that the hand
holds objects (tests.hold_rig)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np
import pytest

from hsqbench.assets.config import load_assets_config
from hsqbench.sim.physics import load_physics_config
from hsqbench.sim.robot import (
    ARM_ACTUATORS,
    ARM_JOINTS,
    Panda,
    load_panda_spec,
    load_robot_config,
    menagerie_path,
)
from tests.hold_rig import FinderConfig, GraspSpec, find_top_down_grasp, run_hold_test

try:
    menagerie_path(load_robot_config())
except FileNotFoundError as exc:  # pragma: no cover - depends on the machine
    pytest.skip(f"Menagerie not available: {exc}", allow_module_level=True)


@dataclass
class BoxAsset:
    """An ObjectLike box written to disk (object frame: base on z = 0, xy centred)."""

    name: str
    mass_kg: float
    com: np.ndarray
    inertia: np.ndarray
    extents: np.ndarray
    visual_mesh: Path
    texture: None
    rgba: tuple[float, float, float, float]
    collision_meshes: tuple[Path, ...]


def make_box(folder: Path, extents, mass_kg: float, name: str = "box") -> BoxAsset:
    import trimesh

    a, b, c = extents
    mesh = trimesh.creation.box(extents=extents)
    mesh.apply_translation([0.0, 0.0, c / 2])
    path = folder / f"{name}.obj"
    mesh.export(path)
    inertia = mass_kg / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return BoxAsset(
        name,
        mass_kg,
        np.array([0.0, 0.0, c / 2]),
        inertia,
        np.array(extents, float),
        path,
        None,
        (0.8, 0.3, 0.2, 1.0),
        (path,),
    )


def robot_model(realistic: bool = True, gravcomp: bool = True) -> tuple[mujoco.MjModel, Panda]:
    cfg = dataclasses.replace(
        load_robot_config(), realistic_hand=realistic, gravity_compensation=gravcomp
    )
    spec = mujoco.MjSpec()
    from hsqbench.sim.physics import apply_physics

    apply_physics(spec, load_physics_config())
    spec.attach(load_panda_spec(cfg), prefix=cfg.prefix, frame=spec.worldbody.add_frame())
    model = spec.compile()
    return model, Panda(model, cfg.prefix)


def test_arm_is_menagerie_unchanged() -> None:
    raw = mujoco.MjModel.from_xml_path(str(menagerie_path(load_robot_config())))
    model, panda = robot_model()
    for name in ARM_ACTUATORS:
        a, b = raw.actuator(name), model.actuator(panda.prefix + name)
        for field in ("gainprm", "biasprm", "ctrlrange", "forcerange"):
            np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=name)
    for name in ARM_JOINTS:
        a, b = raw.joint(name), model.joint(panda.prefix + name)
        np.testing.assert_array_equal(a.range, b.range)
        np.testing.assert_array_equal(a.armature, b.armature)
        np.testing.assert_array_equal(a.damping, b.damping)
    np.testing.assert_allclose(raw.body_mass.sum(), model.body_mass.sum())
    np.testing.assert_allclose(panda.home_arm_q, raw.key("home").qpos[:7])


def test_gripper_replaced_and_pads_made_rubber() -> None:
    cfg = load_robot_config()
    model, panda = robot_model()
    assert panda.gripper_actuator_name == cfg.prefix + "gripper"
    names = [model.actuator(i).name for i in range(model.nu)]
    assert cfg.prefix + "actuator8" not in names
    f_max = cfg.gripper.max_force_per_finger_n
    np.testing.assert_allclose(
        model.actuator_forcerange[panda.gripper_actuator_id], [-2 * f_max, 2 * f_max]
    )
    pads = [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] in panda.finger_body_ids
        and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
    ]
    assert len(pads) == 10
    np.testing.assert_allclose(model.geom_friction[pads], np.tile(cfg.pads.friction, (10, 1)))
    assert set(model.geom_condim[pads]) == {cfg.pads.condim}


def test_tcp_frame_convention() -> None:
    """x = closing axis (toward the left finger), z = approach (palm -> fingertips), y = z × x,
    origin between the fingertip pads."""
    model, panda = robot_model()
    data = mujoco.MjData(model)
    panda.reset_home(data)
    mujoco.mj_forward(model, data)
    pos, rot = panda.tcp_pose(data)
    left, right = data.xpos[panda.finger_body_ids]
    closing = (left - right) / np.linalg.norm(left - right)
    np.testing.assert_allclose(rot[:, 0], closing, atol=1e-9)
    hand = data.xpos[panda.hand_body_id]
    approach = (pos - hand) / np.linalg.norm(pos - hand)
    np.testing.assert_allclose(rot[:, 2], approach, atol=1e-9)
    np.testing.assert_allclose(rot[:, 1], np.cross(rot[:, 2], rot[:, 0]), atol=1e-9)
    big_pads = [
        g
        for g in range(model.ngeom)
        if model.geom_bodyid[g] in panda.finger_body_ids
        and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
        and model.geom_size[g, 0] > 0.008
    ]
    pad_centre = data.geom_xpos[big_pads].mean(axis=0)
    assert np.linalg.norm(pad_centre - pos) < 1e-3


def test_gripper_width_commands_follow_the_filter_without_jumps() -> None:
    model, panda = robot_model()
    data = mujoco.MjData(model)
    panda.reset_home(data)
    dt = model.opt.timestep
    tau = load_robot_config().gripper.target_time_constant_s
    start, goal = panda.gripper_width(data), 0.05

    def run(seconds: float) -> np.ndarray:
        widths = []
        for _ in range(round(seconds / dt)):
            mujoco.mj_step(model, data)
            widths.append(panda.gripper_width(data))
        return np.array(widths)

    panda.set_gripper(data, goal)
    widths = run(6 * tau)
    assert abs(widths[-1] - goal) < 1e-3
    peak_rate = np.max(np.abs(np.diff(widths))) / dt
    expected = abs(start - goal) / tau  # initial rate of the first-order filter
    assert 0.7 * expected < peak_rate < 1.3 * expected
    panda.close_gripper(data)
    assert run(6 * tau)[-1] < 1e-3
    panda.open_gripper(data)
    assert run(6 * tau)[-1] > panda.max_width() - 1e-3


def test_home_is_held_still_with_gravity_compensation() -> None:
    def drift(gravcomp: bool) -> float:
        model, panda = robot_model(gravcomp=gravcomp)
        data = mujoco.MjData(model)
        panda.reset_home(data)
        mujoco.mj_forward(model, data)
        start = panda.tcp_pose(data)[0]
        for _ in range(round(1.0 / model.opt.timestep)):
            mujoco.mj_step(model, data)
        return float(np.linalg.norm(panda.tcp_pose(data)[0] - start))

    assert drift(True) < 1e-3
    assert drift(False) > 3e-3  # why gravity compensation is one of the modifications


def test_arm_targets_are_checked() -> None:
    model, panda = robot_model()
    data = mujoco.MjData(model)
    panda.set_arm_targets(data, panda.home_arm_q)
    np.testing.assert_allclose(data.ctrl[panda.arm_actuator_ids], panda.home_arm_q)
    bad = panda.home_arm_q.copy()
    bad[3] = 0.5  # joint 4 must stay below -0.0698 rad
    with pytest.raises(ValueError, match="joints \\[4\\]"):
        panda.set_arm_targets(data, bad)
    with pytest.raises(ValueError, match="7 finite"):
        panda.set_arm_targets(data, np.full(7, np.nan))


def test_squeeze_force_is_the_real_hands(tmp_path: Path) -> None:
    """A flat-sided box: the pads press with the configured 70 N; Menagerie's hand with ~1.6 N."""
    box = make_box(tmp_path, (0.06, 0.08, 0.1), 0.3)
    grasp = GraspSpec(yaw_rad=0.0, height_m=0.07)
    f_max = load_robot_config().gripper.max_force_per_finger_n
    real = run_hold_test(box, grasp)
    np.testing.assert_allclose(real.finger_force_n, [f_max, f_max], rtol=0.02)
    assert real.held
    assert abs(real.width_m - 0.06) < 2e-3
    raw = dataclasses.replace(load_robot_config(), realistic_hand=False)
    weak = run_hold_test(box, grasp, robot=raw)
    assert np.all(weak.finger_force_n < 3.0)


def test_grasp_finder_rejects_an_object_wider_than_the_hand(tmp_path: Path) -> None:
    box = make_box(tmp_path, (0.1, 0.1, 0.05), 0.2, name="wide")
    with pytest.raises(ValueError, match="no top-down grasp fits"):
        find_top_down_grasp(box, FinderConfig())


def make_leaning_wall(folder: Path, lean_deg: float = 20.0, mass_kg: float = 0.15) -> BoxAsset:
    """A bowl's rim in miniature: a 3 mm wall leaning ``lean_deg`` outwards (+x) on a base plate
    that reaches 6 cm inwards, so the centre of mass hangs beside the wall like a bowl's. Both
    are 10 cm long (y), wider than the hand opens: the wall can only be pinched across."""
    import trimesh

    base = trimesh.creation.box(extents=(0.10, 0.10, 0.01))
    base.apply_translation([-0.01, 0.0, 0.005])
    wall = trimesh.creation.box(extents=(0.003, 0.10, 0.05))
    lean = np.radians(lean_deg)
    wall.apply_transform(trimesh.transformations.rotation_matrix(lean, [0.0, 1.0, 0.0]))
    wall.apply_translation([0.04 + 0.025 * np.sin(lean), 0.0, 0.01 + 0.025 * np.cos(lean)])
    parts = [base, wall]
    lo, hi = (
        np.min([m.bounds[0] for m in parts], axis=0),
        np.max([m.bounds[1] for m in parts], axis=0),
    )
    shift = np.array([-(lo[0] + hi[0]) / 2, -(lo[1] + hi[1]) / 2, -lo[2]])
    paths = []
    for k, mesh in enumerate(parts):
        mesh.apply_translation(shift)
        paths.append(folder / f"leaning_{k}.obj")
        mesh.export(paths[-1])
    whole = trimesh.util.concatenate(parts)
    whole.density = mass_kg / whole.volume
    return BoxAsset(
        "leaning_wall",
        mass_kg,
        np.asarray(whole.center_mass),
        np.asarray(whole.moment_inertia),
        hi - lo,
        paths[0],
        None,
        (0.8, 0.3, 0.2, 1.0),
        tuple(paths),
    )


# Closing axes across and along the leaning wall only: at the finder's 4 mm sampling, a pinch
# 22.5 deg off the normal of a 3 mm plate passes its squareness test (a limit of the sampling).
WALL_FINDER = FinderConfig(yaw_steps=2)


def test_grasp_finder_tilts_the_hand_to_a_leaning_wall(tmp_path: Path) -> None:
    """Straight down, the pads would meet the leaning wall at opposite edges; the finder tilts
    the hand until the closing axis is square to the wall (within one pitch step)."""
    finder = WALL_FINDER
    obj = make_leaning_wall(tmp_path)
    grasp = find_top_down_grasp(obj, finder)
    lean = np.radians(20.0)
    wall_up = np.array([np.sin(lean), 0.0, np.cos(lean)])
    closing = np.array(
        [
            np.cos(grasp.pitch_rad) * np.cos(grasp.yaw_rad),
            np.cos(grasp.pitch_rad) * np.sin(grasp.yaw_rad),
            np.sin(grasp.pitch_rad),
        ]
    )
    assert abs(closing @ wall_up) < np.sin(finder.pitch_step_rad)
    assert abs(grasp.pitch_rad) > lean - finder.pitch_step_rad
    assert grasp.offset_m[0] > 0.02  # on the wall, not the base plate
    upright = make_box(tmp_path, (0.06, 0.08, 0.1), 0.3)
    assert find_top_down_grasp(upright, finder).pitch_rad == 0.0


def test_a_pinch_on_a_leaning_wall_turns_it_and_a_square_one_holds(tmp_path: Path) -> None:
    """The physics behind the tilt: squeezed straight down, the wall turns in the hand until it
    lies flat on the pads (the centre of mass swings centimetres); squeezed square, it holds."""
    obj = make_leaning_wall(tmp_path)
    square = find_top_down_grasp(obj, WALL_FINDER)
    straight = dataclasses.replace(square, pitch_rad=0.0)
    held = run_hold_test(obj, square)
    turned = run_hold_test(obj, straight)
    assert held.held, held
    assert held.slip_m < 0.002
    assert not turned.held
    assert turned.slip_m > 0.01


def _ycb_or_skip(name: str):
    from hsqbench.settings import ycb_dir

    if ycb_dir(required=False) is None:
        pytest.skip("HSQ_YCB_DIR is not set: YCB objects unavailable")
    from hsqbench.assets.library import get_object

    return get_object(name)


# Fast set: the heaviest object plus a box and a procedural cylinder, whose builds take seconds.
FAST_HOLD = ["bleach_cleanser", "sugar_box", "proc_cylinder"]


def _hold(name: str):
    if name.startswith("proc_"):
        from hsqbench.assets.library import get_object

        obj = get_object(name)
    else:
        obj = _ycb_or_skip(name)
    return run_hold_test(obj, find_top_down_grasp(obj))


@pytest.mark.parametrize("name", FAST_HOLD)
def test_hand_holds_object_through_a_lift(name: str) -> None:
    result = _hold(name)
    assert result.held, result
    assert result.slip_m < 0.005
    assert result.lifted_m > 0.14


def test_menagerie_hand_drops_the_bleach_bottle() -> None:
    obj = _ycb_or_skip("bleach_cleanser")
    raw = dataclasses.replace(load_robot_config(), realistic_hand=False)
    result = run_hold_test(obj, find_top_down_grasp(obj), robot=raw)
    assert not result.held
    assert result.lifted_m < 0.05


#: The benchmark's 15 YCB objects (configs/assets.yaml), the set the slow check covers.
YCB_OBJECTS = [o.name for o in load_assets_config().download.objects]


@pytest.mark.slow
@pytest.mark.parametrize("name", YCB_OBJECTS)
def test_hand_holds_every_ycb_object(name: str) -> None:
    result = _hold(name)
    assert result.held, result
