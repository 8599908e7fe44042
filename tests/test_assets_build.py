"""Building one object: pose, mass properties, hulls, writing, cache (hsqbench.assets.build)."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh

from hsqbench.assets import build as build_mod
from hsqbench.assets.asset import ObjectAsset
from hsqbench.assets.build import (
    AssetError,
    AssetWarning,
    ObjectSpec,
    build_object,
    cache_key,
    clean_hulls,
    drop_fins,
    is_closed_oriented,
    mass_properties,
)
from hsqbench.assets.config import AssetsConfig, HullConfig, ProceduralObject, load_assets_config
from hsqbench.assets.mjcf import object_mjcf

L_SIZE = (0.10, 0.08, 0.03, 0.04)


@pytest.fixture
def fast_config() -> AssetsConfig:
    """The project config with CoACD effort cut down so a small mesh decomposes in about a second."""
    config = load_assets_config()
    coacd = dataclasses.replace(
        config.coacd, preprocess_resolution=20, resolution=500, mcts_iterations=20, mcts_nodes=10
    )
    return dataclasses.replace(config, coacd=coacd)


def _proc_spec(kind: str, size: tuple[float, ...], name: str = "obj") -> ObjectSpec:
    return ObjectSpec(
        name=name,
        source="procedural",
        density_kg_m3=400.0,
        procedural=ProceduralObject(name=name, kind=kind, size_m=size),
        sections=32,
    )


def _load_obj(path: Path) -> trimesh.Trimesh:
    return trimesh.load(path, force="mesh", process=False)


def test_box_mass_properties_match_the_closed_form():
    mesh = trimesh.creation.box(extents=(0.05, 0.07, 0.10))
    props = mass_properties(mesh, mass_kg=0.3, density_kg_m3=None, label="box")
    a, b, c = 0.05, 0.07, 0.10
    expected = 0.3 / 12 * np.diag([b**2 + c**2, a**2 + c**2, a**2 + b**2])
    assert props.method == "mesh"
    assert props.volume_m3 == pytest.approx(a * b * c)
    np.testing.assert_allclose(props.inertia, expected, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(props.com, 0.0, atol=1e-12)


def test_mass_from_density_when_no_mass_is_given():
    mesh = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    props = mass_properties(mesh, mass_kg=None, density_kg_m3=500.0, label="cube")
    assert props.mass_kg == pytest.approx(0.5)


def test_open_mesh_uses_the_convex_hull_and_says_so():
    mesh = trimesh.creation.box(extents=(0.1, 0.1, 0.1))
    open_mesh = trimesh.Trimesh(mesh.vertices, mesh.faces[:-2])
    assert not is_closed_oriented(open_mesh)
    with pytest.warns(AssetWarning, match="not a closed surface"):
        props = mass_properties(open_mesh, mass_kg=1.0, density_kg_m3=None, label="open box")
    assert props.method == "convex_hull"
    assert props.volume_m3 == pytest.approx(1e-3)


def test_non_manifold_but_closed_surface_counts_as_closed():
    # Two cubes sharing one edge: that edge has four faces (non-manifold), yet the surface is closed.
    a = trimesh.creation.box(extents=(1, 1, 1))
    b = a.copy()
    b.apply_translation((1, 1, 0))
    both = trimesh.util.concatenate([a, b])
    both.merge_vertices()
    assert not both.is_watertight
    assert is_closed_oriented(both)


def test_dangling_fin_faces_are_dropped_to_close_the_surface():
    box = trimesh.creation.box(extents=(1, 1, 1))
    a, b = box.faces[0][:2]
    fin_tip = box.vertices[[a, b]].mean(axis=0) + np.array([0.0, 0.0, 5.0])
    vertices = np.vstack([box.vertices, fin_tip])
    faces = np.vstack([box.faces, [a, b, len(box.vertices)]])
    finned = trimesh.Trimesh(vertices, faces, process=False)
    assert not is_closed_oriented(finned)
    fixed = drop_fins(finned)
    assert is_closed_oriented(fixed)
    assert len(fixed.faces) == 12 and fixed.volume == pytest.approx(1.0)


def test_clean_hulls_merges_slivers_and_drops_nothing_solid():
    big = trimesh.creation.box(extents=(0.1, 0.1, 0.1)).vertices
    sliver = np.array([[0.06, 0, 0], [0.061, 0, 0], [0.06, 0.001, 0], [0.06, 0, 0.001]])
    flat = np.array([[0.35, 0, 0], [0.45, 0, 0], [0.35, 0.1, 0], [0.45, 0.1, 0]])  # coplanar
    far = big + np.array([0.5, 0, 0])
    hulls = clean_hulls(
        [big, sliver, flat, far], HullConfig(min_volume_fraction=0.01, min_volume_m3=0)
    )
    assert len(hulls) == 2
    assert all(h.is_convex and h.volume > 0 for h in hulls)
    # The sliver joined the big cube (its nearest neighbour), so that hull now reaches x = 0.061.
    assert max(h.bounds[1, 0] for h in hulls if h.bounds[0, 0] < 0.1) == pytest.approx(0.061)


def test_clean_hulls_of_only_degenerate_parts_is_empty():
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    assert clean_hulls([flat, flat.copy()], HullConfig()) == []


def test_l_builds_in_the_object_frame_with_several_hulls(tmp_path, fast_config):
    asset = build_object(_proc_spec("l", L_SIZE), fast_config, tmp_path)
    ax, ay, w, h = L_SIZE
    np.testing.assert_allclose(asset.extents, [ax, ay, h], atol=1e-9)
    visual = _load_obj(asset.visual_mesh)
    np.testing.assert_allclose(
        visual.bounds, [[-ax / 2, -ay / 2, 0], [ax / 2, ay / 2, h]], atol=1e-7
    )
    # COM of the L (two rectangles), shifted into the bounding-box-centred frame.
    areas = np.array([ax * w, (ay - w) * w])
    centres = np.array([[ax / 2, w / 2], [w / 2, w + (ay - w) / 2]])
    com_xy = areas @ centres / areas.sum() - [ax / 2, ay / 2]
    np.testing.assert_allclose(asset.com, [*com_xy, h / 2], atol=1e-9)
    assert asset.mass_kg == pytest.approx(400.0 * areas.sum() * h)
    assert len(asset.collision_meshes) >= 2
    hull_volume = 0.0
    for path in asset.collision_meshes:
        hull = _load_obj(path)
        assert hull.is_convex and hull.volume > 1e-8
        assert (hull.bounds[0] >= visual.bounds[0] - 2e-3).all()
        assert (hull.bounds[1] <= visual.bounds[1] + 2e-3).all()
        hull_volume += hull.volume
    # Hulls cover the L without filling its notch (whose hull would be ax * ay * h).
    assert areas.sum() * h * 0.95 < hull_volume < 0.8 * ax * ay * h
    assert asset.info["inertia_method"] == "mesh"
    assert asset.info["collision_method"] == "coacd"


def test_built_object_compiles_and_comes_to_rest_on_the_floor(tmp_path, fast_config):
    asset = build_object(_proc_spec("l", L_SIZE), fast_config, tmp_path)
    model = mujoco.MjModel.from_xml_string(object_mjcf(asset, drop_height_m=0.02))
    data = mujoco.MjData(model)
    body = model.body(asset.name).id
    assert model.body_mass[body] == pytest.approx(asset.mass_kg)
    np.testing.assert_allclose(model.body_ipos[body], asset.com, atol=1e-9)
    for _ in range(int(1.0 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    # Resting flat: the body origin (base of the object frame) is back on z = 0, not sunk or tipped.
    assert abs(data.xpos[body][2]) < 2e-3
    np.testing.assert_allclose(data.xmat[body].reshape(3, 3)[:, 2], [0, 0, 1], atol=1e-2)
    assert np.linalg.norm(data.qvel) < 1e-2


def test_second_build_is_a_cache_hit(tmp_path, fast_config, monkeypatch):
    spec = _proc_spec("box", (0.05, 0.06, 0.07))
    first = build_object(spec, fast_config, tmp_path)
    monkeypatch.setattr(
        build_mod, "decompose", lambda *a, **k: pytest.fail("rebuilt a cached object")
    )
    second = build_object(spec, fast_config, tmp_path)
    assert second.build_dir == first.build_dir
    np.testing.assert_array_equal(second.inertia, first.inertia)


def test_cache_key_follows_inputs_and_parameters(tmp_path, fast_config):
    spec = _proc_spec("box", (0.05, 0.06, 0.07))
    key = cache_key(spec, fast_config)
    assert cache_key(spec, fast_config) == key
    other = dataclasses.replace(fast_config, coacd=dataclasses.replace(fast_config.coacd, seed=1))
    assert cache_key(spec, other) != key
    assert cache_key(_proc_spec("box", (0.05, 0.06, 0.08)), fast_config) != key
    mesh = tmp_path / "m.stl"
    trimesh.creation.box(extents=(0.1, 0.1, 0.1)).export(mesh)
    file_spec = ObjectSpec(name="m", source="imported", mesh_path=mesh, density_kg_m3=500.0)
    k1 = cache_key(file_spec, fast_config)
    trimesh.creation.box(extents=(0.1, 0.1, 0.2)).export(mesh)
    assert cache_key(file_spec, fast_config) != k1


def test_failed_build_leaves_no_cache_entry(tmp_path, fast_config, monkeypatch):
    calls = []

    def write_then_die(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 2:
            raise KeyboardInterrupt  # as if the build were killed half-way through writing
        return original(path, *args, **kwargs)

    original = build_mod.write_obj
    monkeypatch.setattr(build_mod, "write_obj", write_then_die)
    spec = _proc_spec("l", L_SIZE)
    with pytest.raises(KeyboardInterrupt):
        build_object(spec, fast_config, tmp_path)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setattr(build_mod, "write_obj", original)
    assert isinstance(build_object(spec, fast_config, tmp_path), ObjectAsset)


def test_coacd_failure_falls_back_to_the_convex_hull(tmp_path, fast_config, monkeypatch):
    import coacd

    def broken(*args, **kwargs):
        raise RuntimeError("simulated CoACD crash")

    monkeypatch.setattr(coacd, "run_coacd", broken)
    with pytest.warns(AssetWarning, match="simulated CoACD crash"):
        asset = build_object(_proc_spec("l", L_SIZE), fast_config, tmp_path)
    assert len(asset.collision_meshes) == 1
    assert asset.info["collision_method"] == "convex_hull"
    hull = _load_obj(asset.collision_meshes[0])
    ax, ay, w, h = L_SIZE
    # The hull of an L prism: its bounding box less the triangle cut off the notch corner.
    assert hull.volume == pytest.approx((ax * ay - (ax - w) * (ay - w) / 2) * h, rel=1e-6)


def test_broken_mesh_names_its_file(tmp_path, fast_config):
    bad = tmp_path / "broken.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\n")  # no faces
    spec = ObjectSpec(name="broken", source="imported", mesh_path=bad, density_kg_m3=500.0)
    with pytest.raises(AssetError, match=r"broken\.obj"):
        build_object(spec, fast_config, tmp_path / "cache")
    garbage = tmp_path / "garbage.stl"
    garbage.write_bytes(os.urandom(50))
    spec = ObjectSpec(name="garbage", source="imported", mesh_path=garbage, density_kg_m3=500.0)
    with pytest.raises(AssetError, match=r"garbage\.stl"):
        build_object(spec, fast_config, tmp_path / "cache")
    flat = tmp_path / "flat.obj"
    flat.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    spec = ObjectSpec(name="flat", source="imported", mesh_path=flat, density_kg_m3=500.0)
    with pytest.raises(AssetError, match=r"flat\.obj"):
        build_object(spec, fast_config, tmp_path / "cache")


def test_spec_rejects_bad_parameters():
    with pytest.raises(ValueError, match="up must be one of"):
        ObjectSpec(name="x", source="imported", mesh_path=Path("x.obj"), density_kg_m3=1.0, up="w")
    with pytest.raises(ValueError, match="positive mass_kg or density"):
        ObjectSpec(name="x", source="imported", mesh_path=Path("x.obj"))
    with pytest.raises(ValueError, match="scale"):
        ObjectSpec(name="x", source="imported", mesh_path=Path("x.obj"), density_kg_m3=1.0, scale=0)
