"""Pile scenes (hsqbench.sim.scene.pile): seeded heaps at rest on the table, redraws recorded."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from hsqbench.sim.physics import load_physics_config
from hsqbench.sim.robot import load_robot_config, menagerie_path
from hsqbench.sim.scene import (
    PileConfig,
    PileError,
    build_scene,
    hull_vertices,
    load_scene_config,
    pile_placeable,
    pile_scene,
)
from hsqbench.sim.scene import pile as pile_module

try:
    menagerie_path(load_robot_config())
except FileNotFoundError as exc:  # pragma: no cover - depends on the machine
    pytest.skip(f"Menagerie not available: {exc}", allow_module_level=True)

# No sphere: a ball rolls on (no rolling friction) until it leaves the workspace.
OBJECTS = ["proc_box", "proc_cylinder", "proc_l", "proc_mug"]


@pytest.fixture(autouse=True)
def _fresh_cache():
    pile_scene._CACHE.clear()
    yield
    pile_scene._CACHE.clear()


def _vertices(model, data, info, name):
    from hsqbench.assets.library import get_object

    b = info.object_body_ids[name]
    return hull_vertices(get_object(name)) @ data.xmat[b].reshape(3, 3).T + data.xpos[b]


def _touching_pairs(model, data, info) -> set[tuple[int, int]]:
    ids = set(info.object_body_ids.values())
    pairs = set()
    for c in data.contact[: data.ncon]:
        a, b = model.geom_bodyid[c.geom1], model.geom_bodyid[c.geom2]
        if a in ids and b in ids and a != b:
            pairs.add((min(a, b), max(a, b)))
    return pairs


def test_pile_is_deterministic_per_seed() -> None:
    _, _, a = build_scene("pile", OBJECTS, seed=3)
    pile_scene._CACHE.clear()  # a real second drop, not the remembered one
    _, _, b = build_scene("pile", OBJECTS, seed=3)
    _, _, c = build_scene("pile", OBJECTS, seed=4)
    for name in OBJECTS:
        np.testing.assert_array_equal(a.initial_poses[name], b.initial_poses[name])
    assert a.rejected_drops == b.rejected_drops
    assert any(not np.allclose(a.initial_poses[n], c.initial_poses[n]) for n in OBJECTS)
    assert a.kind == "pile" and a.objects == OBJECTS


def test_pile_objects_rest_on_the_table_inside_the_workspace_and_heap() -> None:
    """Every object at rest, above the table top, inside the workspace; and heaped: in a box
    too small for the four side by side, some rest on others or touch them."""
    base = load_scene_config()
    small = dataclasses.replace(base, pile=dataclasses.replace(base.pile, box_size_m=(0.12, 0.12)))
    model, data, info = build_scene("pile", OBJECTS, seed=0, scene_config=small)
    physics = load_physics_config()
    assert info.max_speed_after_settle < physics.settle_speed_mps
    # Still at rest half a second later, with the arm holding home.
    for _ in range(round(0.5 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    ids = np.array(list(info.object_body_ids.values()))
    assert np.abs(data.cvel[ids]).max() < 2 * physics.settle_speed_mps
    stacked = 0
    for name in OBJECTS:
        v = _vertices(model, data, info, name)
        assert v[:, 2].min() > info.table_top_z - 0.005, name
        assert np.all(v[:, :2] >= info.workspace_min[:2]) and np.all(
            v[:, :2] <= info.workspace_max[:2]
        ), name
        stacked += v[:, 2].min() > info.table_top_z + 0.01
    assert stacked > 0 or _touching_pairs(model, data, info)


def test_a_rejected_drop_is_redrawn_from_the_same_generator_and_recorded(monkeypatch) -> None:
    _, _, first = build_scene("pile", OBJECTS, seed=7)
    pile_scene._CACHE.clear()
    real = pile_module._problem
    calls = []

    def reject_first(drop, speed):
        calls.append(1)
        return "rejected for the test" if len(calls) == 1 else real(drop, speed)

    monkeypatch.setattr(pile_module, "_problem", reject_first)
    _, _, redrawn = build_scene("pile", OBJECTS, seed=7)
    assert redrawn.rejected_drops[0] == "rejected for the test"
    assert redrawn.rejected_drops[1:] == first.rejected_drops[: len(redrawn.rejected_drops) - 1]
    # The next drop of the generator, not the rejected one again.
    assert any(not np.allclose(first.initial_poses[n], redrawn.initial_poses[n]) for n in OBJECTS)


def test_a_pile_that_cannot_settle_is_refused_by_the_check_and_an_error_for_the_builder() -> None:
    base = load_scene_config()
    hasty = dataclasses.replace(
        base, pile=dataclasses.replace(base.pile, settle_time_s=0.02, max_drop_attempts=2)
    )
    assert not pile_placeable(OBJECTS, 1, hasty)
    with pytest.raises(PileError, match="in 2 drops") as err:
        build_scene("pile", OBJECTS, seed=1, scene_config=hasty)
    assert "still moves" in str(err.value)
    assert pile_placeable(OBJECTS, 1, base) == (
        build_scene("pile", OBJECTS, seed=1, scene_config=base)[2].kind == "pile"
    )


def test_pile_config_errors_name_the_key() -> None:
    with pytest.raises(ValueError, match=r"pile\.n_objects"):
        PileConfig(n_objects=0)
    with pytest.raises(ValueError, match="box_size_m"):
        PileConfig(box_size_m=(0.3, 0.0))
    with pytest.raises(ValueError, match="max_drop_attempts"):
        PileConfig(max_drop_attempts=0)
    base = load_scene_config()
    wide = dataclasses.replace(base, pile=dataclasses.replace(base.pile, box_size_m=(0.5, 0.3)))
    with pytest.raises(ValueError, match=r"must fit inside workspace\.size_m"):
        build_scene("pile", OBJECTS, seed=0, scene_config=wide)


def test_objects_that_fit_no_orientation_between_the_walls_are_named() -> None:
    base = load_scene_config()
    tiny = dataclasses.replace(
        base,
        pile=dataclasses.replace(
            base.pile, box_size_m=(0.02, 0.02), max_drop_attempts=1, max_orientation_tries=5
        ),
    )
    with pytest.raises(PileError, match="no orientation of 5 fits"):
        build_scene("pile", OBJECTS, seed=0, scene_config=tiny)


def test_scene_command_builds_a_pile(tmp_path, capsys) -> None:
    from PIL import Image

    from hsqbench.cli import main

    out, xml = tmp_path / "pile.png", tmp_path / "mjcf"
    args = [
        "scene",
        "--scene",
        "pile",
        "--objects",
        *OBJECTS[:3],
        "--png",
        str(out),
        "--mjcf",
        str(xml),
    ]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert text.startswith("pile scene, seed 0: proc_box, proc_cylinder, proc_l")
    image = np.asarray(Image.open(out).convert("RGB"), dtype=float)
    assert image.std() > 10.0
    # The exported scene is the ordinary one: the objects at their settled poses, no walls.
    model = mujoco.MjModel.from_xml_path(str(xml / "scene.xml"))
    names = [model.geom(i).name for i in range(model.ngeom)]
    assert not any(n.startswith(pile_module.WALL_PREFIX) for n in names)
    _, _, info = build_scene("pile", OBJECTS[:3], seed=0)
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("initial").id)
    mujoco.mj_forward(model, data)
    for name in OBJECTS[:3]:
        b = model.body(f"obj/{name}").id
        # MJCF writes 6 significant digits.
        np.testing.assert_allclose(data.xpos[b], info.initial_poses[name][:3], atol=1e-6)


def test_the_pile_is_checked_again_in_the_final_scene_with_the_robot(monkeypatch) -> None:
    """A drop that rests in the drop model but not in the scene with the robot is redrawn too."""
    real = pile_scene.heap_problem
    calls = []

    def reject_first(*args):
        calls.append(1)
        return "moved for the test" if len(calls) == 1 else real(*args)

    monkeypatch.setattr(pile_scene, "heap_problem", reject_first)
    _, _, info = build_scene("pile", OBJECTS, seed=7)
    assert "in the scene with the robot, moved for the test" in info.rejected_drops
    assert info.max_speed_after_settle < load_physics_config().settle_speed_mps
