"""Perception from two depth cameras (hsqbench.sim.perception).

Most checks use a tiny MJCF of our own (a table plane, a box or spheres, two cameras on the two
sides) rendered at a reduced resolution; one check uses the benchmark scene with a procedural box.
"""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.sim.camera import backproject, transform_points
from hsqbench.sim.perception import (
    CropConfig,
    Perception,
    PerceptionConfig,
    fuse_and_downsample,
    load_perception_config,
    refit_table_plane,
)
from hsqbench.sim.scene import DepthCamera
from tests.shapes import Box

W, H, FOVY = 320, 240, 55.0
WS_MIN = np.array([0.3, -0.25, 0.0])
WS_MAX = np.array([0.7, 0.25, 0.3])
PLANE = np.array([0.0, 0.0, 1.0, 0.0])
CAMERAS = (
    DepthCamera("cam_left", W, H, FOVY, 0.3, 3.0),
    DepthCamera("cam_right", W, H, FOVY, 0.3, 3.0),
)
CAM_POS = {"cam_left": (0.62, 0.75, 0.55), "cam_right": (0.62, -0.75, 0.55)}
TARGET = np.array([0.5, 0.0, 0.05])

BOX_HALF = (0.03, 0.04, 0.05)
BOX_YAW_DEG = 30.0
BOX_POS = np.array([0.5, 0.02, 0.05])
SPHERES = np.array([[0.42, -0.12, 0.12], [0.58, 0.14, 0.2], [0.5, 0.0, 0.07], [0.62, -0.15, 0.25]])
SPHERE_R = 0.02
ROBOT_POS = np.array([0.4, 0.15, 0.1])


def _xyaxes(pos, target) -> str:
    z = np.asarray(pos, float) - target  # MuJoCo cameras look along -z
    z /= np.linalg.norm(z)
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return " ".join(f"{v:.9f}" for v in (*x, *y))


def tiny_model(body_xml: str) -> mujoco.MjModel:
    cams = "".join(
        f'<camera name="{n}" pos="{" ".join(map(str, p))}" xyaxes="{_xyaxes(p, TARGET)}" '
        f'fovy="{FOVY}" resolution="{W} {H}"/>'
        for n, p in CAM_POS.items()
    )
    xml = f"""<mujoco>
      <visual><global offwidth="{W}" offheight="{H}"/></visual>
      <worldbody>
        <geom name="table" type="plane" size="1 1 0.01" pos="0.5 0 0"/>
        {body_xml}
        {cams}
      </worldbody>
    </mujoco>"""
    return mujoco.MjModel.from_xml_string(xml)


def _forward(model):
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return data


BOX_XML = (
    f'<geom name="box" type="box" size="{" ".join(map(str, BOX_HALF))}" '
    f'pos="{" ".join(map(str, BOX_POS))}" euler="0 0 {BOX_YAW_DEG}"/>'
)
ROBOT_XML = f'<geom name="robot" type="sphere" size="0.03" pos="{" ".join(map(str, ROBOT_POS))}"/>'
SPHERES_XML = "".join(
    f'<geom type="sphere" size="{SPHERE_R}" pos="{" ".join(map(str, c))}"/>' for c in SPHERES
)


def _box() -> Box:
    yaw = np.deg2rad(BOX_YAW_DEG)
    R = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    return Box(BOX_HALF, R, BOX_POS)


def _config(sensor_model: str = "none", **kwargs) -> PerceptionConfig:
    return replace(load_perception_config(), sensor_model=sensor_model, **kwargs)


def _perception(model, config, seed=0, **kwargs) -> Perception:
    return Perception(
        model,
        CAMERAS,
        support_plane=PLANE,
        workspace_min=WS_MIN,
        workspace_max=WS_MAX,
        rng=np.random.default_rng(seed),
        config=config,
        **kwargs,
    )


@pytest.fixture(scope="module")
def box_scene():
    model = tiny_model(BOX_XML)
    return model, _forward(model)


@pytest.fixture(scope="module")
def clean_box(box_scene):
    model, data = box_scene
    with _perception(model, _config("none")) as perception:
        yield perception.observe(data, np.random.default_rng(0))


def test_noiseless_fused_cloud_lies_on_the_box_and_holds_no_table(clean_box):
    obs = clean_box
    d = _box().distance(obs.points)
    assert len(obs.points) > 500
    assert d.max() < 0.002
    # No table: the table is z = 0 and every point is on the box above the removal margin.
    assert obs.points[:, 2].min() > load_perception_config().crop.table_margin_m - 1e-9
    assert obs.points.dtype == np.float64 and obs.points.shape[1] == 3


def test_each_camera_sees_its_own_side_of_the_box(clean_box):
    obs = clean_box
    assert set(np.unique(obs.camera_index)) == {0, 1}
    box = _box()
    local = (obs.points - box.center) @ box.rotation
    side = np.sign(local @ (box.rotation.T @ [0.0, 1.0, 0.0]))  # world +y side of the box
    left = obs.camera_index == 0  # cam_left is at +y
    assert np.mean(side[left] > 0) > 0.6
    assert np.mean(side[~left] < 0) > 0.6
    for view in obs.cameras:
        assert view.depth_m.shape == (H, W) and view.depth_m.dtype == np.float32
        assert view.n_cropped > 0 and view.n_valid_px > view.n_cropped
        assert np.allclose(view.T_world_camera, view.T_world_camera_true)


def _sphere_centre(points: np.ndarray) -> np.ndarray:
    """Algebraic least-squares sphere fit: |p|^2 = 2 p.c + k."""
    A = np.column_stack([2 * points, np.ones(len(points))])
    sol, *_ = np.linalg.lstsq(A, np.sum(points**2, axis=1), rcond=None)
    return sol[:3]


def test_known_geoms_appear_at_their_world_coordinates_in_both_cameras():
    model = tiny_model(SPHERES_XML)
    data = _forward(model)
    with _perception(model, _config("none")) as perception:
        depths = perception.render_depth(data)
        obs = perception.observe(data, np.random.default_rng(0))
    for view, depth in zip(obs.cameras, depths, strict=True):
        valid = depth > 0
        world = transform_points(view.T_world_camera, backproject(depth, view.K)[valid])
        for centre in SPHERES:
            near = world[np.linalg.norm(world - centre, axis=1) < 1.5 * SPHERE_R]
            assert len(near) > 50, f"{view.name} does not see the sphere at {centre}"
            # The points lie on the sphere, and the sphere they span has the true centre:
            # a wrong focal length, principal point or axis flip moves it by millimetres.
            assert np.abs(np.linalg.norm(near - centre, axis=1) - SPHERE_R).max() < 5e-4
            assert np.linalg.norm(_sphere_centre(near) - centre) < 5e-4
            # And the visible cap faces the camera.
            towards = (view.position - centre) / np.linalg.norm(view.position - centre)
            assert np.mean((near - centre) @ towards) > 0.5 * SPHERE_R


def test_sensor_errors_are_deterministic_per_seed(box_scene):
    model, data = box_scene
    cfg = _config("tof+calibration")
    with _perception(model, cfg, seed=3) as a, _perception(model, cfg, seed=3) as b:
        oa = a.observe(data, np.random.default_rng(9))
        ob = b.observe(data, np.random.default_rng(9))
        oc = a.observe(data, np.random.default_rng(10))
        assert np.array_equal(a.camera_errors, b.camera_errors)
    assert np.array_equal(oa.points, ob.points)
    assert np.array_equal(oa.camera_index, ob.camera_index)
    assert not np.array_equal(oa.points, oc.points)
    with _perception(model, cfg, seed=4) as other:
        assert not np.allclose(other.camera_errors, a.camera_errors)


def test_calibration_error_moves_each_camera_and_the_table_is_still_removed(box_scene):
    model, data = box_scene
    cfg = _config("calibration")
    with _perception(model, cfg, seed=1) as perception:
        obs = perception.observe(data, np.random.default_rng(0))
        errors = perception.camera_errors
    box = _box()
    shifts = []
    for i, view in enumerate(obs.cameras):
        assert np.allclose(view.T_world_camera, view.T_world_camera_true @ errors[i])
        shifts.append(view.T_world_camera[:3, 3] - view.T_world_camera_true[:3, 3])
        assert np.linalg.norm(shifts[-1]) == pytest.approx(cfg.calibration.translation_m)
    assert not np.allclose(shifts[0], shifts[1])
    # 0.4 deg at ~0.9 m plus 2.5 mm: points move by up to ~9 mm, but none of the table remains.
    d = box.distance(obs.points)
    assert np.percentile(d, 95) < 0.01
    assert d.max() < 0.015


def test_default_noisy_cloud_stays_near_the_box(box_scene):
    model, data = box_scene
    with _perception(model, load_perception_config(), seed=2) as perception:
        obs = perception.observe(data, np.random.default_rng(2))
    d = _box().distance(obs.points)
    assert len(obs.points) > 300
    # The calibration error alone moves points by up to 0.4 deg x 0.95 m + 2.5 mm = 9 mm.
    assert np.percentile(d, 90) < 0.009
    # Flying pixels along the silhouettes are the outliers (3-4 % on seeds 0-7).
    outliers = np.mean(d > 0.015)
    assert 0.005 < outliers < 0.07


def test_robot_pixels_are_dropped_by_segmentation():
    model = tiny_model(BOX_XML + ROBOT_XML)
    data = _forward(model)
    robot = [model.geom("robot").id]
    near_robot = []
    for drop in (False, True):
        cfg = _config("none", drop_robot_pixels=drop)
        with _perception(model, cfg, robot_geom_ids=robot) as perception:
            obs = perception.observe(data, np.random.default_rng(0))
        near_robot.append(int(np.sum(np.linalg.norm(obs.points - ROBOT_POS, axis=1) < 0.035)))
    assert near_robot[0] > 100 and near_robot[1] == 0


def test_empty_table_gives_an_empty_cloud():
    model = tiny_model("")
    data = _forward(model)
    with _perception(model, _config("tof")) as perception:
        obs = perception.observe(data, np.random.default_rng(0))
    assert obs.points.shape == (0, 3) and obs.camera_index.shape == (0,)


def test_table_refit_recovers_a_shifted_tilted_table():
    rng = np.random.default_rng(0)
    xy = rng.uniform([0.3, -0.25], [0.7, 0.25], size=(5000, 2))
    tilt = np.deg2rad(0.4)
    z = 0.006 + np.tan(tilt) * (xy[:, 0] - 0.5) + rng.normal(0, 0.001, len(xy))
    table = np.column_stack([xy, z])
    obj = np.column_stack([rng.uniform(0.45, 0.5, (800, 2)), rng.uniform(0.0, 0.1, 800)])
    plane = refit_table_plane(np.vstack([table, obj]), PLANE, CropConfig())
    heights = table @ plane[:3] + plane[3]
    assert abs(np.mean(heights)) < 3e-4
    assert np.std(heights) < 0.0012
    # Too few points near the nominal table: keep the nominal plane.
    assert np.array_equal(refit_table_plane(obj[:100], PLANE, CropConfig()), PLANE)


def test_fusion_labels_each_voxel_with_its_main_camera():
    a = np.array([[0.0, 0.0, 0.0], [0.0005, 0.0, 0.0], [0.1, 0.0, 0.0]])
    b = np.array([[0.0003, 0.0, 0.0], [0.2, 0.0, 0.0]])
    points, index = fuse_and_downsample([a, b], voxel_m=0.002)
    order = np.argsort(points[:, 0])
    assert np.allclose(points[order, 0], [0.0008 / 3, 0.1, 0.2])
    assert list(index[order]) == [0, 0, 1]


def test_config_file_loads_and_bad_values_are_named():
    cfg = load_perception_config()
    assert cfg.sensor_model == "tof+calibration" and cfg.tof_on and cfg.calibration_on
    with pytest.raises(ConfigError, match="sensor_model"):
        from_dict(PerceptionConfig, {"sensor_model": "lidar"})
    with pytest.raises(ConfigError, match="voxel_m"):
        from_dict(PerceptionConfig, {"voxel_m": 0.0})


def test_bad_inputs_are_refused_with_the_fix(box_scene):
    model, _ = box_scene
    with pytest.raises(ValueError, match="cameras: "):
        Perception(
            model,
            (DepthCamera("nope", W, H, FOVY, 0.3, 3.0),),
            support_plane=PLANE,
            workspace_min=WS_MIN,
            workspace_max=WS_MAX,
            rng=np.random.default_rng(0),
            config=_config(),
        )
    with pytest.raises(ValueError, match="width_px"):
        _perception_with(model, (DepthCamera("cam_left", 640, H, FOVY, 0.3, 3.0),))
    with pytest.raises(ValueError, match="normal"):
        Perception(
            model,
            CAMERAS,
            support_plane=[0, 0, 0, 1],
            workspace_min=WS_MIN,
            workspace_max=WS_MAX,
            rng=np.random.default_rng(0),
            config=_config(),
        )
    with pytest.raises(ValueError, match="robot_geom_ids"):
        _perception(model, _config(drop_robot_pixels=True))


def _perception_with(model, cameras):
    return Perception(
        model,
        cameras,
        support_plane=PLANE,
        workspace_min=WS_MIN,
        workspace_max=WS_MAX,
        rng=np.random.default_rng(0),
        config=_config(),
    )


def test_closed_perception_refuses_to_render(box_scene):
    model, data = box_scene
    perception = _perception(model, _config())
    perception.close()
    perception.close()
    with pytest.raises(RuntimeError, match="closed"):
        perception.observe(data, np.random.default_rng(0))


def test_benchmark_scene_box_is_perceived_without_table_or_robot():
    from hsqbench.sim.scene import build_scene

    model, data, info = build_scene("isolated", "proc_box", seed=1)
    body = info.object_body_ids["proc_box"]
    R = data.xmat[body].reshape(3, 3)
    box = Box((0.025, 0.035, 0.05), R, data.xpos[body] + R @ [0.0, 0.0, 0.05])
    with Perception.from_scene(
        model, info, rng=np.random.default_rng(0), config=_config("none")
    ) as perception:
        assert perception.camera_names == info.camera_names
        obs = perception.observe(data, np.random.default_rng(0))
    d = box.distance(obs.points)
    assert len(obs.points) > 1000
    assert d.max() < 0.002  # no table, no robot, nothing but the box
    assert set(np.unique(obs.camera_index)) == {0, 1}
    assert obs.camera_positions.shape == (2, 3)


@pytest.mark.parametrize("camera", ["cam_left", "cam_right"])
def test_single_camera_mode_perceives_with_that_camera_only_and_the_planners_still_plan(camera):
    from hsqbench.planner.api import PlanningContext
    from hsqbench.planner.registry import get_planner
    from hsqbench.sim.scene import build_scene
    from hsqbench.sim.trial import load_trial_config

    scene = load_trial_config("trial", {"scene.depth_cameras.names": [camera]}).scene
    model, data, info = build_scene("isolated", "proc_box", seed=1, scene_config=scene)
    assert info.camera_names == (camera,)
    with Perception.from_scene(model, info, rng=np.random.default_rng(0)) as perception:
        obs = perception.observe(data, np.random.default_rng(0))
    assert [c.name for c in obs.cameras] == [camera]
    assert obs.camera_positions.shape == (1, 3)
    true_pos = data.cam_xpos[model.camera(camera).id]
    assert np.linalg.norm(obs.camera_positions[0] - true_pos) < 0.01  # calibration error only
    assert len(obs.points) > 300 and set(np.unique(obs.camera_index)) == {0}
    # one side of the box only: its far side (seen by the other camera) is missing
    both_model, both_data, both_info = build_scene("isolated", "proc_box", seed=1)
    with Perception.from_scene(both_model, both_info, rng=np.random.default_rng(0)) as both:
        full = both.observe(both_data, np.random.default_rng(0))
    assert len(obs.points) < 0.8 * len(full.points)
    context = PlanningContext(
        support_plane=tuple(obs.support_plane),
        camera_positions=obs.camera_positions,
        workspace_bounds=(obs.workspace_min, obs.workspace_max),
    )
    # the paper's method completes the hidden side; the antipodal baseline may find no pair of
    # seen contacts on one view of a box, and must say so rather than fail
    assert len(get_planner("hsq").plan(obs.points, context).grasps) > 0
    antipodal = get_planner("antipodal").plan(obs.points, context)
    assert len(antipodal.grasps) > 0 or antipodal.reason
