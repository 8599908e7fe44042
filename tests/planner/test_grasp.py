"""The Grasp record: frame convention, validation, contacts and JSON round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hsqbench.planner.grasp import GRASP_TO_MENAGERIE_HAND, Grasp


def make(rotation=None, **kwargs) -> Grasp:
    rot = Rotation.from_rotvec([0.3, -0.2, 0.9]).as_matrix() if rotation is None else rotation
    args = {"position": [0.5, 0.1, 0.05], "rotation": rot, "width": 0.04, "score": 0.7}
    args.update(kwargs)
    return Grasp(**args)


def test_axes_are_the_rotation_columns_and_contacts_straddle_p_g() -> None:
    g = make()
    np.testing.assert_allclose(g.closing_axis, g.rotation[:, 0])
    np.testing.assert_allclose(g.approach_axis, g.rotation[:, 2])
    # Third axis = approach x closing (right-handed columns).
    np.testing.assert_allclose(np.cross(g.approach_axis, g.closing_axis), g.rotation[:, 1])
    a, b = g.contacts()
    np.testing.assert_allclose(b - a, 0.04 * g.closing_axis)
    np.testing.assert_allclose((a + b) / 2, g.position)


@pytest.mark.parametrize(
    ("kwargs", "needle"),
    [
        ({"rotation": np.diag([1.0, 1.0, -1.0])}, "proper rotation"),
        ({"rotation": np.diag([1.0, 2.0, 1.0])}, "proper rotation"),
        ({"position": [0.0, np.nan, 0.0]}, "finite"),
        ({"width": -0.01}, "width"),
        ({"width": float("inf")}, "width"),
        ({"width": 0.05, "approach_width": 0.04}, "approach_width"),
    ],
)
def test_invalid_grasps_are_refused(kwargs, needle) -> None:
    with pytest.raises(ValueError, match=needle):
        make(**kwargs)


def test_json_round_trip() -> None:
    g = make(factors={"h_alpha": 0.9, "h_beta": 0.8}, source=3, family="slide", approach_width=0.06)
    back = Grasp.from_dict(json.loads(json.dumps(g.to_dict())))
    assert back.approach_width == 0.06
    assert np.isnan(Grasp.from_dict(make().to_dict()).approach_width)  # unknown stays unknown
    np.testing.assert_allclose(back.position, g.position)
    np.testing.assert_allclose(back.rotation, g.rotation)
    assert (back.width, back.score, back.factors, back.source, back.family) == (
        g.width,
        g.score,
        g.factors,
        3,
        "slide",
    )


def test_menagerie_hand_frame_maps_closing_to_y_and_approach_to_z() -> None:
    g = make()
    hand = g.rotation @ GRASP_TO_MENAGERIE_HAND
    assert np.linalg.det(hand) == pytest.approx(1.0)
    np.testing.assert_allclose(hand[:, 1], g.closing_axis)
    np.testing.assert_allclose(hand[:, 2], g.approach_axis)
