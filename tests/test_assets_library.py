"""The library interface: names, lookup, get_object, parallel builds (hsqbench.assets.library)."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from PIL import Image

from hsqbench.assets.config import load_assets_config
from hsqbench.assets.library import (
    UnknownObjectError,
    build_objects,
    get_object,
    is_built,
    object_names,
    ycb_names,
)
from hsqbench.assets.mjcf import object_mjcf

PAPER_15 = [
    o.name for o in load_assets_config().download.objects
]  # the paper's 15 (configs/assets.yaml)
PROCEDURAL = ["proc_box", "proc_cylinder", "proc_sphere", "proc_l", "proc_mug"]
YCB = os.environ.get("HSQ_YCB_DIR")
needs_ycb = pytest.mark.skipif(not YCB or not Path(YCB).is_dir(), reason="HSQ_YCB_DIR is not set")


USER_CACHE = os.environ.get("HSQ_CACHE_DIR")


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.fixture
def fast_config():
    config = load_assets_config()
    coacd = dataclasses.replace(
        config.coacd, preprocess_resolution=20, resolution=500, mcts_iterations=20, mcts_nodes=10
    )
    return dataclasses.replace(config, coacd=coacd)


def test_procedural_objects_are_always_known(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    assert object_names() == PROCEDURAL
    assert object_names("procedural") == PROCEDURAL
    assert object_names("ycb") == []


@needs_ycb
def test_ycb_names_come_first_in_csv_order():
    csv_names = [
        line.split(",")[0]
        for line in (Path(YCB) / "objects.csv").read_text().splitlines()[1:]
        if line.strip()
    ]
    names = ycb_names()
    # Every listed object whose mesh is present, in the CSV's order, whatever the folder's size.
    assert names == [n for n in csv_names if n in names]
    assert set(PAPER_15) <= set(names)
    assert object_names() == [*names, *PROCEDURAL]
    assert object_names("ycb") == names


def test_unknown_source_and_name_list_the_known_ones():
    with pytest.raises(ValueError, match="unknown source 'shapenet'"):
        object_names("shapenet")
    with pytest.raises(UnknownObjectError, match=r"known objects: .*proc_box.*proc_mug"):
        get_object("teapot")


def test_ycb_name_without_ycb_dir_explains_how_to_get_the_meshes(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    with pytest.raises(
        UnknownObjectError, match=r"'mug' is a YCB object.*hsqbench assets download"
    ):
        get_object("mug")


def test_get_object_without_build_says_how_to_build(fast_config):
    with pytest.raises(FileNotFoundError, match="hsqbench assets build proc_box"):
        get_object("proc_box", build=False, config=fast_config)
    assert not is_built("proc_box", fast_config)
    built = get_object("proc_box", config=fast_config)
    assert is_built("proc_box", fast_config)
    again = get_object("proc_box", build=False, config=fast_config)
    assert again.build_dir == built.build_dir
    assert built.source == "procedural" and built.texture is None
    np.testing.assert_allclose(built.extents, [0.05, 0.07, 0.10])
    assert built.mass_kg == pytest.approx(400.0 * 0.05 * 0.07 * 0.10)


def test_parallel_build_gives_the_same_assets_as_a_serial_one(fast_config, cache, monkeypatch):
    names = ["proc_l", "proc_cylinder"]
    parallel = build_objects(names, jobs=2, config=fast_config, progress=False)
    assert [a.name for a in parallel] == names
    monkeypatch.setenv("HSQ_CACHE_DIR", str(cache.parent / "serial"))
    serial = build_objects(names, jobs=1, config=fast_config, progress=False)
    for p, s in zip(parallel, serial, strict=True):
        assert p.build_dir.name == s.build_dir.name  # same cache key
        np.testing.assert_allclose(p.inertia, s.inertia)
        assert len(p.collision_meshes) == len(s.collision_meshes)
        for a, b in zip(p.collision_meshes, s.collision_meshes, strict=True):
            assert a.read_text() == b.read_text()  # seeded CoACD: identical hulls


@needs_ycb
def test_cracker_box_builds_textured_in_its_object_frame(fast_config):
    asset = get_object("cracker_box", config=fast_config)
    assert asset.source == "ycb"
    assert asset.mass_kg == pytest.approx(0.411)
    assert asset.texture is not None
    with Image.open(asset.texture) as image:
        assert image.size[0] >= 256
    visual = trimesh.load(asset.visual_mesh, force="mesh", process=False)
    assert len(visual.visual.uv) == len(visual.vertices)
    lo, hi = visual.bounds
    assert lo[2] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose((lo[:2] + hi[:2]) / 2, 0.0, atol=1e-9)
    np.testing.assert_allclose(asset.extents, hi - lo, atol=1e-9)
    # A full box of uniform density: COM near the middle, principal moments of a 7 x 16 x 21 cm box.
    np.testing.assert_allclose(asset.com, [0, 0, asset.extents[2] / 2], atol=0.01)
    a, b, c = asset.extents
    box = asset.mass_kg / 12 * np.array([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    np.testing.assert_allclose(np.sort(np.linalg.eigvalsh(asset.inertia)), np.sort(box), rtol=0.15)
    model = mujoco.MjModel.from_xml_string(object_mjcf(asset))
    assert model.ntex == 1 and model.nmesh == 1 + len(asset.collision_meshes)


@pytest.mark.slow
@needs_ycb
def test_every_object_of_the_folder_builds_and_compiles(monkeypatch):
    """Every YCB object of HSQ_YCB_DIR (any number) and every procedural one, with the project
    parameters: CoACD takes minutes per new object, so this uses the real, content-addressed
    cache (as `make assets` does) and is quick once the library is built."""
    from hsqbench.assets.library import failure_message, prepare_objects

    if USER_CACHE:
        monkeypatch.setenv("HSQ_CACHE_DIR", USER_CACHE)
    else:
        monkeypatch.delenv("HSQ_CACHE_DIR")
    names = ycb_names() + PROCEDURAL
    report = prepare_objects(names, progress=False)
    assert not report.failed, failure_message(report.failed)
    assert list(report.assets) == names
    for asset in report.assets.values():
        assert 1 <= len(asset.collision_meshes) <= load_assets_config().coacd.max_convex_hull
        if asset.name in PAPER_15:  # a new object may fall back to its convex hull (warned)
            assert asset.info["collision_method"] == "coacd", asset.name
        model = mujoco.MjModel.from_xml_string(object_mjcf(asset))
        assert model.body(asset.name).mass[0] == pytest.approx(asset.mass_kg)


@pytest.mark.parametrize("jobs", [1, 2])
def test_an_object_that_cannot_be_built_is_reported_and_the_others_still_build(
    fast_config, cache, tmp_path, jobs
):
    from hsqbench.assets.build import AssetError
    from hsqbench.assets.importer import register
    from hsqbench.assets.library import prepare_objects

    folder = tmp_path / "meshes"
    folder.mkdir()
    (folder / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    register(folder, cache, set(PROCEDURAL), density_kg_m3=500.0)
    report = prepare_objects(["proc_box", "flat"], jobs=jobs, config=fast_config, progress=False)
    assert list(report.assets) == ["proc_box"]
    assert set(report.failed) == {"flat"}
    assert "AssetError" in report.failed["flat"] and "flat.obj" in report.failed["flat"]
    assert "\n" not in report.failed["flat"]
    with pytest.raises(AssetError, match=r"1 object\(s\) cannot be built:\n  flat: AssetError"):
        build_objects(["proc_box", "flat"], jobs=jobs, config=fast_config, progress=False)
    with pytest.raises(UnknownObjectError, match="teapot"):
        prepare_objects(["proc_box", "teapot"], config=fast_config, progress=False)


def test_build_progress_in_a_log_is_one_line_per_object(fast_config, capsys):
    from hsqbench.assets.library import prepare_objects

    prepare_objects(["proc_box", "proc_sphere"], jobs=1, config=fast_config, progress=True)
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = [line for line in err.splitlines() if line.startswith("objects ")]
    assert [line.split(":")[0] for line in lines] == ["objects 1/2", "objects 2/2"]
    assert "built proc_box in" in lines[0]
    prepare_objects(["proc_box", "proc_sphere"], jobs=1, config=fast_config, progress=True)
    assert "objects" not in capsys.readouterr().err  # all cached: nothing to show


def test_resting_poses_of_a_box_are_its_six_faces_larger_ones_likelier(fast_config):
    import numpy as np

    from hsqbench.assets.resting import FILE_NAME, resting_poses

    build_objects(["proc_box"], jobs=1, config=fast_config)
    box = get_object("proc_box", config=fast_config)
    poses = resting_poses(box)
    assert len(poses.probabilities) == 6
    assert poses.probabilities.sum() == pytest.approx(1.0)
    # Height of the box in each pose; the lower it lies, the likelier the pose.
    heights = np.abs(poses.rotations[:, 2, :]) @ box.extents
    assert np.all(np.diff(heights) >= -1e-6)
    assert set(np.round(heights, 3)) == set(np.round(box.extents, 3))
    assert (box.build_dir / FILE_NAME).exists()  # cached beside the built asset


def _dies_on_sphere(spec, config, root):
    """A builder whose process dies on proc_sphere (as a crash in CoACD would)."""
    if spec.name == "proc_sphere":
        os._exit(3)
    from hsqbench.assets.library import _build_one

    return _build_one(spec, config, root)


def test_a_build_process_that_dies_is_pinned_on_its_object(fast_config, cache):
    from hsqbench.assets.library import BUILD_DIED, _builds, object_spec

    names = ["proc_box", "proc_sphere", "proc_cylinder", "proc_l"]
    specs = [object_spec(n, fast_config) for n in names]
    results = {
        name: (asset, error)
        for name, asset, error, _ in _builds(specs, fast_config, cache, 2, _dies_on_sphere)
    }
    assert set(results) == set(names)  # every object answered once
    assert results["proc_sphere"] == (None, BUILD_DIED)
    for name in ("proc_box", "proc_cylinder", "proc_l"):
        asset, error = results[name]
        assert error is None and asset.name == name
