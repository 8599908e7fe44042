"""The YCB source: objects.csv and the 15 meshes of HSQ_YCB_DIR (hsqbench.assets.ycb).

Nothing here runs CoACD on a YCB mesh except the one small build (cracker box, about 3 s) and
the slow test that builds the whole set.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import trimesh

from hsqbench.assets.build import ObjectSpec, is_closed_oriented, load_mesh
from hsqbench.assets.config import load_assets_config
from hsqbench.assets.ycb import read_objects_csv, ycb_entries
from hsqbench.settings import SettingError

YCB = os.environ.get("HSQ_YCB_DIR")
needs_ycb = pytest.mark.skipif(not YCB or not Path(YCB).is_dir(), reason="HSQ_YCB_DIR is not set")


@needs_ycb
def test_lists_the_configured_objects_in_csv_order_with_the_configured_masses():
    entries = {e.name: e for e in ycb_entries()}
    configured = load_assets_config().download.objects
    # The paper's 15 (configs/assets.yaml) are all there with the official ids and masses, whatever
    # else the folder holds; the CSV order is kept (the library test checks it).
    assert all(o.name in entries for o in configured)
    assert [entries[o.name].ycb_id for o in configured] == [o.ycb_id for o in configured]
    np.testing.assert_allclose(
        [entries[o.name].mass_kg for o in configured], [o.mass_kg for o in configured]
    )


@needs_ycb
@pytest.mark.parametrize("entry", ycb_entries(required=False), ids=lambda e: e.name)
def test_each_mesh_loads_in_metres_with_z_up_and_a_texture(entry):
    mesh = trimesh.load(entry.mesh_path, force="mesh", process=False)
    assert len(mesh.faces) > 1000
    extents = mesh.extents
    # YCB objects are 1.5 cm (dice) to 35 cm across: the file is in metres, not millimetres
    # (a millimetre file would read 15-350 m) nor centimetres (1.5-35 m).
    assert 0.01 < extents.max() < 0.5
    # Canonical YCB frame: the object stands on (about) z = 0.
    assert abs(mesh.bounds[0, 2]) < 0.01
    assert entry.texture_path is not None
    assert len(mesh.visual.uv) == len(mesh.vertices)
    # After cleaning, the solid is closed, so the inertia comes from the mesh, not a fallback.
    spec = ObjectSpec(
        name=entry.name, source="ycb", mesh_path=entry.mesh_path, mass_kg=entry.mass_kg
    )
    loaded = load_mesh(spec)
    assert is_closed_oriented(loaded.solid)
    assert loaded.solid.volume == pytest.approx(mesh.volume, rel=1e-3)
    assert loaded.texture_file == entry.texture_path


def test_missing_folder_explains_both_ways_to_get_the_meshes(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    with pytest.raises(SettingError, match="HSQ_YCB_DIR is not set") as err:
        ycb_entries()
    assert "hsqbench assets download" in str(err.value)
    assert ycb_entries(required=False) == []


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("name,mass_kg\nmug,0.1\n", r"missing column\(s\) \['ycb_id'\]"),
        ("name,ycb_id,mass_kg\nmug,025,-1\n", "line 2"),
        ("name,ycb_id,mass_kg\nmug,025,abc\n", "positive mass_kg"),
        ("name,ycb_id,mass_kg\nmug,025,0.1\nmug,025,0.1\n", "duplicate"),
    ],
)
def test_bad_objects_csv_names_the_problem(tmp_path, text, match):
    (tmp_path / "objects.csv").write_text(text)
    with pytest.raises(ValueError, match=match):
        read_objects_csv(tmp_path)


def test_missing_objects_csv_says_what_it_needs(tmp_path):
    with pytest.raises(FileNotFoundError, match="name,ycb_id,mass_kg"):
        read_objects_csv(tmp_path)
