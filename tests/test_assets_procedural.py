"""Procedural objects: closed meshes of the configured sizes (hsqbench.assets.procedural)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hsqbench.assets.build import is_closed_oriented
from hsqbench.assets.config import ProceduralObject, load_assets_config
from hsqbench.assets.procedural import make_mesh, procedural_names

SECTIONS = 96


def _volume(obj: ProceduralObject) -> float:
    s = obj.size_m
    if obj.kind == "box":
        return s[0] * s[1] * s[2]
    if obj.kind == "cylinder":
        return math.pi * s[0] ** 2 * s[1]
    if obj.kind == "sphere":
        return 4 / 3 * math.pi * s[0] ** 3
    if obj.kind == "l":
        ax, ay, w, h = s
        return (ax * w + (ay - w) * w) * h
    radius, height, wall, rh, width = s
    cup = math.pi * (radius**2 * height - (radius - wall) ** 2 * (height - wall))
    return cup + math.pi * rh * wall * width  # half-torus-like handle: arc length pi*rh


def test_config_lists_the_five_shapes():
    config = load_assets_config().procedural
    assert procedural_names(config) == [
        "proc_box",
        "proc_cylinder",
        "proc_sphere",
        "proc_l",
        "proc_mug",
    ]


@pytest.mark.parametrize("obj", load_assets_config().procedural.objects, ids=lambda o: o.name)
def test_mesh_is_closed_with_the_expected_volume(obj):
    mesh = make_mesh(obj, SECTIONS)
    assert is_closed_oriented(mesh)
    assert mesh.volume > 0
    # Faceting loses a little volume on curved shapes (icosphere: about 1 %).
    assert mesh.volume == pytest.approx(_volume(obj), rel=0.02)


def test_mug_handle_sticks_out_on_plus_x():
    obj = next(o for o in load_assets_config().procedural.objects if o.kind == "mug")
    mesh = make_mesh(obj, SECTIONS)
    radius, _, wall, rh, _ = obj.size_m
    assert mesh.bounds[1, 0] == pytest.approx(radius + rh + wall / 2, rel=1e-6)
    assert mesh.bounds[0, 0] == pytest.approx(-radius, rel=1e-3)


@pytest.mark.parametrize(
    ("kind", "size", "match"),
    [
        ("box", (0.1, 0.1), "takes 3 sizes"),
        ("sphere", (-0.1,), "must be > 0"),
        ("cone", (0.1,), "unknown procedural kind"),
        ("l", (0.1, 0.1, 0.2, 0.05), "arm width"),
        ("mug", (0.04, 0.09, 0.03, 0.03, 0.01), "do not fit"),
    ],
)
def test_bad_sizes_are_named(kind, size, match):
    with pytest.raises(ValueError, match=match):
        make_mesh(ProceduralObject(name="bad", kind=kind, size_m=size), SECTIONS)


def test_l_is_not_convex():
    obj = ProceduralObject(name="l", kind="l", size_m=(0.1, 0.08, 0.03, 0.04))
    mesh = make_mesh(obj, SECTIONS)
    assert mesh.convex_hull.volume > 1.3 * mesh.volume
    assert np.allclose(mesh.bounds, [[0, 0, 0], [0.1, 0.08, 0.04]])
