"""The vgn and giga planners' view-faithful input (``input: per_view``): each camera's image
alone, in cubes yawed so that the camera lies on their -y side, as the published weights were
trained (needs torch and the weights for all but the first test)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.learned import volumetric
from tests.volumetric_scene import BOX, CAMERAS, TABLE, box_cloud, planner_or_skip, render

VOXEL_M = 0.0075


def _yaw(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize("camera", [[0.62, 0.78, 0.55], [0.62, -0.78, 0.55], [-0.3, 0.1, 0.5]])
def test_the_yaw_puts_the_camera_on_the_cubes_minus_y_side(camera):
    centre = np.array([0.5, 0.02])
    R = volumetric.view_yaw(np.array(camera), centre)
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    assert np.allclose(R[:, 2], [0, 0, 1])  # about the vertical only
    seen = (np.array(camera) - np.r_[centre, 0.0]) @ R  # the camera in the cubes' frame
    assert abs(seen[0]) < 1e-9 and seen[1] < 0 and seen[2] == pytest.approx(camera[2])


@pytest.fixture(scope="module", params=["vgn", "giga"])
def per_view(request):
    base = planner_or_skip(request.param)
    return type(base)(request.param, dataclasses.replace(base.config, input="per_view"))


def _plan(planner, boxes, views, cloud=None):
    context = PlanningContext(support_plane=TABLE, seed=0, scene="isolated", depth_views=views)
    return planner.plan(box_cloud(boxes) if cloud is None else cloud, context)


def test_a_scene_yawed_with_its_cameras_gives_the_grasps_yawed(per_view):
    """Everything rotated about the vertical by 37 deg: every depth image is the same, the
    camera poses and the cloud turn; the grasps turn with them (within a voxel)."""
    views = tuple(render(c, [BOX]) for c in CAMERAS)
    R = _yaw(np.deg2rad(37.0))
    turned = tuple(
        dataclasses.replace(v, T_world_camera=np.vstack([R @ v.T_world_camera[:3], [0, 0, 0, 1]]))
        for v in views
    )
    first = _plan(per_view, [BOX], views)
    again = _plan(per_view, [BOX], turned, cloud=box_cloud([BOX]) @ R.T)
    assert first.grasps and len(again.grasps) == len(first.grasps)
    for a, b in zip(first.grasps, again.grasps, strict=True):
        assert np.linalg.norm(R @ a.position - b.position) < VOXEL_M
        assert np.allclose(R @ a.rotation, b.rotation, atol=1e-3)
        assert b.score == pytest.approx(a.score, abs=1e-4)


@pytest.mark.parametrize("side", ["+y", "-y"])
def test_a_single_view_from_either_side_grasps_inside_the_box(per_view, side):
    """One camera alone, from +y or from -y: the top grasp's P_G lies in the box and its
    closing line crosses it (the fused input from +y alone put vgn's 5 cm outside, on the
    camera's side)."""
    camera = CAMERAS[0] if side == "+y" else CAMERAS[1]
    assert np.sign(camera[1]) == (1 if side == "+y" else -1)
    result = _plan(per_view, [BOX], (render(camera, [BOX]),))
    assert result.grasps, result.reason
    best = result.grasps[0]
    lo, hi = BOX
    assert np.all(best.position > lo - 0.005) and np.all(best.position < hi + 0.005)
    with np.errstate(divide="ignore"):
        t0 = (lo - best.position) / best.closing_axis
        t1 = (hi - best.position) / best.closing_axis
    near, far = np.max(np.minimum(t0, t1)), np.min(np.maximum(t0, t1))
    assert near < 0 < far and far - near < 0.08


def test_two_views_run_separately_and_merge_by_quality(per_view):
    views = tuple(render(c, [BOX]) for c in CAMERAS)
    both = _plan(per_view, [BOX], views)
    alone = [_plan(per_view, [BOX], (v,)) for v in views]
    assert both.remaining["cubes"] == 2  # one cube per view for one object
    scores = [g.score for g in both.grasps]
    assert scores == sorted(scores, reverse=True)
    # The same grasps as each view alone (up to float32 differences of a batch of two cubes).
    merged = sorted((g for r in alone for g in r.grasps), key=lambda g: -g.score)
    assert len(merged) == len(both.grasps) and {len(r.grasps) for r in alone} != {0}
    for a, b in zip(merged, both.grasps, strict=True):
        assert np.allclose(a.position, b.position, atol=1e-5) and a.score == pytest.approx(b.score)


def test_the_input_settings_are_checked():
    from hsqbench.planner.learned.volumetric_config import VolumetricConfig

    assert VolumetricConfig().input == "per_view"
    with pytest.raises(ValueError, match="input must be fused or per_view"):
        VolumetricConfig(input="both")
    with pytest.raises(ValueError, match="needs input: per_view"):
        VolumetricConfig(input="fused", viewpoint="training")
