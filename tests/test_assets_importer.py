"""Importing a folder of meshes (hsqbench.assets.importer) and the ``hsqbench assets`` CLI."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from hsqbench.assets.config import load_assets_config
from hsqbench.assets.importer import imported_specs, object_name, register
from hsqbench.assets.library import get_object, object_names
from hsqbench.cli import main


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    return tmp_path / "cache"


@pytest.fixture
def meshes(tmp_path):
    """A folder with a box in millimetres (stl) and a y-up cylinder (obj in a sub-folder)."""
    folder = tmp_path / "meshes"
    (folder / "Tall Can").mkdir(parents=True)
    trimesh.creation.box(extents=(40.0, 60.0, 80.0)).export(folder / "Block-1.stl")
    cylinder = trimesh.creation.cylinder(radius=20.0, height=100.0, sections=32)
    cylinder.apply_transform(
        trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0])
    )  # axis -> +y
    cylinder.export(folder / "Tall Can" / "textured.obj")
    (folder / "notes.txt").write_text("not a mesh")
    return folder


def test_names_come_from_the_file_or_its_folder(tmp_path):
    assert object_name(tmp_path / "Block-1.stl") == "block_1"
    assert object_name(tmp_path / "Tall Can" / "textured.obj") == "tall_can"
    assert object_name(tmp_path / "a.ply", prefix="my_") == "my_a"


def test_register_scale_up_and_density_reach_the_built_object(meshes, cache):
    specs = register(meshes, cache, reserved=set(), density_kg_m3=800.0, scale=0.001, up="y")
    assert sorted(s.name for s in specs) == ["block_1", "tall_can"]
    assert set(imported_specs(cache)) == {"block_1", "tall_can"}
    assert object_names("imported") == ["block_1", "tall_can"]
    can = get_object("tall_can")
    assert can.source == "imported"
    # The file's +y axis is now up; millimetres became metres; mass = density x volume.
    np.testing.assert_allclose(can.extents, [0.04, 0.04, 0.1], rtol=0.01)
    volume = trimesh.creation.cylinder(radius=0.02, height=0.1, sections=32).volume
    assert can.mass_kg == pytest.approx(800.0 * volume)
    assert can.collision_meshes


def test_names_taken_by_built_in_objects_need_a_prefix(meshes, cache, tmp_path):
    with pytest.raises(ValueError, match=r"\['block_1'\] are taken.*--prefix"):
        register(meshes, cache, reserved={"block_1"}, density_kg_m3=500.0, scale=0.001)
    specs = register(
        meshes, cache, reserved={"block_1"}, density_kg_m3=500.0, scale=0.001, prefix="my_"
    )
    assert {s.name for s in specs} == {"my_block_1", "my_tall_can"}


def test_a_mesh_in_millimetres_is_refused_with_the_scale_that_fixes_it(meshes, cache, capsys):
    with pytest.raises(ValueError) as err:
        register(meshes, cache, reserved=set(), density_kg_m3=500.0)
    assert str(err.value) == (
        "Block-1.stl is 80 m across at --scale 1, over the 1 m a graspable object can span: "
        "looks like millimetres: pass --scale 0.001"
    )
    assert not (cache / "imported").exists()  # nothing registered
    # Scaled twice (metres given --scale 0.001): 0.08 mm, refused with the other fix.
    metres = meshes.parent / "metres"
    metres.mkdir()
    trimesh.creation.box(extents=(0.04, 0.06, 0.08)).export(metres / "block.stl")
    with pytest.raises(ValueError, match=r"under the 5 mm .*: looks like metres: pass --scale 1$"):
        register(metres, cache, reserved=set(), density_kg_m3=500.0, scale=0.001)
    # The CLI says it in one line, exit status 2.
    assert main(["assets", "import", str(meshes), "--no-build"]) == 2
    err_lines = capsys.readouterr().err.strip().splitlines()
    assert err_lines == [
        "hsqbench assets: error: Block-1.stl is 80 m across at --scale 1, over the 1 m a "
        "graspable object can span: looks like millimetres: pass --scale 0.001"
    ]


def test_two_files_with_one_name_are_refused(tmp_path, cache):
    folder = tmp_path / "dup"
    (folder / "a").mkdir(parents=True)
    trimesh.creation.box().export(folder / "x.stl")
    trimesh.creation.box().export(folder / "a" / "x.ply")
    with pytest.raises(ValueError, match=r"several files map to the name\(s\) \['x'\]"):
        register(folder, cache, reserved=set(), density_kg_m3=500.0)


def test_folder_without_meshes_says_so(tmp_path, cache):
    (tmp_path / "empty").mkdir()
    with pytest.raises(FileNotFoundError, match="no mesh files"):
        register(tmp_path / "empty", cache, reserved=set(), density_kg_m3=500.0)


def test_stable_up_puts_a_tilted_plank_flat(tmp_path, cache):
    folder = tmp_path / "plank"
    folder.mkdir()
    plank = trimesh.creation.box(extents=(0.02, 0.1, 0.2))
    plank.apply_transform(trimesh.transformations.rotation_matrix(0.7, [1, 1, 0]))
    plank.export(folder / "plank.stl")
    register(folder, cache, reserved=set(), density_kg_m3=500.0, up="stable")
    asset = get_object("plank")
    assert asset.extents[2] == pytest.approx(0.02, abs=1e-6)


def test_cli_import_list_and_build(meshes, capsys, monkeypatch):
    # Low CoACD effort through a config file, as a user would pass one.
    config = load_assets_config()
    path = meshes.parent / "fast.yaml"
    path.write_text("coacd: {preprocess_resolution: 20, mcts_iterations: 20, mcts_nodes: 10}\n")
    assert config.coacd.mcts_iterations != 20
    rc = main(
        [
            "assets",
            "--config",
            str(path),
            "import",
            str(meshes),
            "--scale",
            "0.001",
            "--density",
            "600",
            "--jobs",
            "1",
        ]
    )
    assert rc == 0
    out = capsys.readouterr().out
    assert "registered 2 object(s): block_1, tall_can" in out
    assert "block_1" in out and "2 objects ready" in out
    assert main(["assets", "--config", str(path), "list", "--source", "imported"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("block_1"))
    assert row.split()[1:3] == ["imported", f"{600 * 0.04 * 0.06 * 0.08:.3f}"]
    assert row.split()[-1] == "yes"
    assert "2 objects, 2 built" in out


def test_cli_errors_are_clear(capsys, tmp_path):
    assert main(["assets", "build", "teapot"]) == 2
    assert "unknown object 'teapot'; known objects: proc_box" in capsys.readouterr().err
    assert main(["assets", "import", str(tmp_path / "nowhere")]) == 2
    assert "is not a folder of meshes" in capsys.readouterr().err
    assert main(["assets", "import", str(tmp_path), "--density", "-1"]) == 2
    assert "--density must be > 0" in capsys.readouterr().err
    assert main(["assets", "build", "--source", "ycb"]) == 2
    assert "HSQ_YCB_DIR is not set" in capsys.readouterr().err


def test_cli_list_shows_mass_before_building(capsys):
    assert main(["assets", "list"]) == 0
    out = capsys.readouterr().out
    row = next(line for line in out.splitlines() if line.startswith("proc_box"))
    assert row.split() == ["proc_box", "procedural", "-", "-", "-", "no"]
    assert "more YCB objects are downloaded into" in out and "hsqbench assets download" in out
