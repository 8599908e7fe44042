"""One GL context per process (hsqbench.sim.depth_renderer): the same images as mujoco.Renderer,
bit for bit, and the same clouds from a fresh and a reused context; an MjrContext kept for the
next model that differs only in poses, and drawn with, gives that model's images too."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from hsqbench.sim import depth_renderer
from hsqbench.sim.depth_renderer import DepthRenderer, gl_context, same_uploads
from hsqbench.sim.perception import Perception, load_perception_config


@pytest.fixture(scope="module")
def scene():
    from hsqbench.sim.scene import build_scene

    model, data, info = build_scene("isolated", "proc_mug", seed=2)
    return model, data, info


def _option(groups=(0, 1, 2)) -> mujoco.MjvOption:
    option = mujoco.MjvOption()
    option.geomgroup[:] = 0
    option.geomgroup[list(groups)] = 1
    option.sitegroup[:] = 0
    return option


def _reference(model, data, cam_id, option, h, w, segmentation=False):
    with mujoco.Renderer(model, h, w) as renderer:
        renderer.update_scene(data, camera=cam_id, scene_option=option)
        if segmentation:
            renderer.enable_segmentation_rendering()
        else:
            renderer.enable_depth_rendering()
        return renderer.render()


def test_depth_and_segmentation_equal_mujoco_renderer_bit_for_bit(scene):
    model, data, info = scene
    option = _option()
    cams = info.depth_cameras
    h, w = cams[0].height_px, cams[0].width_px
    with DepthRenderer(model, h, w) as ours:
        for cam in cams:
            cam_id = model.camera(cam.name).id
            depth = ours.depth(data, cam_id, option)
            ref = _reference(model, data, cam_id, option, h, w)
            assert depth.dtype == np.float32 and depth.shape == (h, w)
            assert np.array_equal(depth, ref)
            assert np.isfinite(depth).all() and (depth > 0).mean() > 0.5
            seg = ours.segmentation(data, cam_id, option)
            assert np.array_equal(seg, _reference(model, data, cam_id, option, h, w, True))
    # the two cameras see different images (the renderer is not stuck on one camera)
    with DepthRenderer(model, h, w) as ours:
        left = ours.depth(data, model.camera(cams[0].name).id, option)
        right = ours.depth(data, model.camera(cams[1].name).id, option)
    assert not np.array_equal(left, right)


def test_renderers_alive_together_each_render_their_own_model(scene):
    model, data, info = scene
    from hsqbench.sim.scene import build_scene

    other_model, other_data, _ = build_scene("isolated", "proc_box", seed=5)
    option = _option()
    cam = info.depth_cameras[0]
    h, w = cam.height_px, cam.width_px
    a = DepthRenderer(model, h, w)
    b = DepthRenderer(other_model, h, w)
    try:
        # interleaved: each call must bind its own buffers
        da = a.depth(data, model.camera(cam.name).id, option)
        db = b.depth(other_data, other_model.camera(cam.name).id, option)
        da2 = a.depth(data, model.camera(cam.name).id, option)
    finally:
        a.close()
        b.close()
    assert np.array_equal(da, da2)
    assert np.array_equal(da, _reference(model, data, model.camera(cam.name).id, option, h, w))
    assert not np.array_equal(da, db)


def test_fresh_and_reused_context_give_identical_clouds(scene):
    model, data, info = scene
    config = load_perception_config()

    def cloud():
        with Perception.from_scene(model, info, rng=np.random.default_rng(4), config=config) as p:
            return p.observe(data, np.random.default_rng(8))

    first = cloud()
    context = gl_context()
    second = cloud()
    assert gl_context() is context  # the second Perception reused the process's context
    assert len(first.points) > 100
    assert np.array_equal(first.points, second.points)
    assert np.array_equal(first.camera_index, second.camera_index)
    for a, b in zip(first.cameras, second.cameras, strict=True):
        assert np.array_equal(a.depth_m, b.depth_m)


def test_closed_renderer_and_bad_input_are_clear_errors(scene):
    model, data, info = scene
    cam = info.depth_cameras[0]
    renderer = DepthRenderer(model, cam.height_px, cam.width_px)
    with pytest.raises(ValueError, match="camera id"):
        renderer.depth(data, model.ncam, _option())
    renderer.close()
    renderer.close()  # idempotent
    with pytest.raises(RuntimeError, match="closed"):
        renderer.depth(data, 0, _option())
    off = model.vis.global_.offwidth
    with pytest.raises(ValueError, match="offscreen buffer"):
        DepthRenderer(model, cam.height_px, off + 1)


def test_a_model_differing_only_in_poses_draws_with_the_kept_context(scene):
    from hsqbench.sim.scene import build_scene

    model, data, info = scene
    moved, moved_data, _ = build_scene("isolated", "proc_mug", seed=3)
    assert not np.array_equal(model.body_pos, moved.body_pos)  # the mug stands elsewhere
    assert same_uploads(model, moved)
    option = _option()
    cam = info.depth_cameras[0]
    h, w = cam.height_px, cam.width_px
    with DepthRenderer(model, h, w) as first:
        first.depth(data, model.camera(cam.name).id, option)
        kept = first._mjr
    with DepthRenderer(moved, h, w) as second:
        assert second._mjr is kept  # nothing uploaded again
        cam_id = moved.camera(cam.name).id
        depth = second.depth(moved_data, cam_id, option)
        seg = second.segmentation(moved_data, cam_id, option)
    assert np.array_equal(depth, _reference(moved, moved_data, cam_id, option, h, w))
    assert np.array_equal(seg, _reference(moved, moved_data, cam_id, option, h, w, True))


def test_other_meshes_get_their_own_context_and_a_busy_kept_one_is_left_alone(scene):
    from hsqbench.sim.scene import build_scene

    model, data, info = scene
    box, box_data, _ = build_scene("isolated", "proc_box", seed=5)
    assert not same_uploads(model, box)
    option = _option()
    cam = info.depth_cameras[0]
    h, w = cam.height_px, cam.width_px
    cam_id = box.camera(cam.name).id
    with DepthRenderer(model, h, w) as mug:
        # the kept context is in use: the box gets a context of its own, freed at its close
        with DepthRenderer(box, h, w) as own:
            assert own._mjr is not mug._mjr
            assert depth_renderer._kept.mjr is mug._mjr
            depth = own.depth(box_data, cam_id, option)
        mug_depth = mug.depth(data, model.camera(cam.name).id, option)
    assert np.array_equal(depth, _reference(box, box_data, cam_id, option, h, w))
    assert np.array_equal(
        mug_depth, _reference(model, data, model.camera(cam.name).id, option, h, w)
    )
    # no renderer draws with the mug's context now: the box's replaces it as the kept one
    with DepthRenderer(box, h, w) as replaced:
        assert depth_renderer._kept.mjr is replaced._mjr
        assert np.array_equal(replaced.depth(box_data, cam_id, option), depth)
