"""The gripper model: config values, box layout, validation, and agreement with Menagerie."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.gripper import GripperModel, load_gripper


def test_config_file_matches_the_documented_defaults() -> None:
    assert load_gripper() == GripperModel()


def test_boxes_place_fingers_at_the_opening_and_palm_behind_the_jaw() -> None:
    g = GripperModel()
    (f_pos, f_neg, palm) = g.boxes(opening_m=0.05)
    assert f_pos[0, 0] == pytest.approx(0.025) and f_neg[1, 0] == pytest.approx(-0.025)
    assert f_pos[1, 0] - f_pos[0, 0] == pytest.approx(g.finger_thickness_m)
    assert f_pos[1, 2] == pytest.approx(g.fingertip_overhang_m)
    assert f_pos[0, 2] == pytest.approx(-g.jaw_length_m) == palm[1, 2]
    assert palm[1, 0] - palm[0, 0] == pytest.approx(g.palm_width_m)
    # Default opening is l_w; the palm extension lengthens the palm backwards only.
    assert g.boxes()[0][0, 0] == pytest.approx(g.max_opening_m / 2)
    swept = g.boxes(palm_extension_m=0.05)[2]
    assert swept[0, 2] == pytest.approx(palm[0, 2] - 0.05) and swept[1, 2] == palm[1, 2]


@pytest.mark.parametrize(
    ("data", "needle"),
    [
        ({"max_opening_m": 0.0}, "max_opening_m"),
        ({"jaw_length_m": -0.01}, "jaw_length_m"),
        ({"palm_width_m": 0.1}, "palm_width_m"),
        ({"fingertip_overhang_m": -0.001}, "fingertip_overhang_m"),
    ],
)
def test_bad_dimensions_name_the_key(data, needle) -> None:
    with pytest.raises(ConfigError, match=needle):
        from_dict(GripperModel, data)


def _menagerie() -> Path | None:
    root = os.environ.get("MENAGERIE_ROOT")
    path = Path(root) / "franka_emika_panda" / "assets" if root else None
    return path if path is not None and (path / "hand.stl").is_file() else None


@pytest.mark.skipif(_menagerie() is None, reason="MENAGERIE_ROOT with franka_emika_panda not set")
def test_dimensions_agree_with_the_menagerie_hand_meshes() -> None:
    trimesh = pytest.importorskip("trimesh")
    assets = _menagerie()
    hand = trimesh.load(assets / "hand.stl", force="mesh")
    finger = trimesh.load(assets / "finger_0.obj", force="mesh")
    g = GripperModel()
    # hand.xml: hand z = approach, hand y = closing; finger bodies at z = 0.0584.
    lo, hi = hand.bounds
    assert hi[1] - lo[1] == pytest.approx(g.palm_width_m, abs=5e-4)
    assert hi[0] - lo[0] == pytest.approx(g.palm_thickness_m, abs=5e-4)
    assert hi[2] - lo[2] == pytest.approx(g.palm_depth_m, abs=5e-4)
    assert g.tcp_offset_m - hi[2] == pytest.approx(g.jaw_length_m, abs=5e-4)
    tip = 0.0584 + finger.bounds[1, 2]
    assert tip - g.tcp_offset_m == pytest.approx(g.fingertip_overhang_m, abs=5e-4)
    assert np.ptp(finger.bounds[:, 0]) == pytest.approx(g.finger_width_m, abs=5e-4)
