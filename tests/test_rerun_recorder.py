"""The Rerun episode recorder: a recorded trial reads back with the documented entities and a
sim_time timeline; recording does not change the trial; a disabled recorder is never called."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.stage_two.candidates import REJECTION_REASONS
from hsqbench.sim.outcome import WALL_CLOCK_FIELDS
from hsqbench.sim.recorder import Recorder
from hsqbench.viz.colors import NO_SCORE_COLOR, REASON_COLORS, score_colors
from hsqbench.viz.config import ViewerConfig, load_viewer_config
from hsqbench.viz.gripper_outline import gripper_outline
from hsqbench.viz.rerun_recorder import RerunRecorder
from hsqbench.viz.rrd import read_recording
from hsqbench.viz.scene_geometry import body_meshes

OBJECT, SEED = "proc_box", 0


def _outcomes(result) -> list[dict]:
    """The attempts without wall-clock timings (which differ from run to run)."""
    return [
        {k: v for k, v in a.to_dict().items() if k not in WALL_CLOCK_FIELDS}
        for a in result.attempts
    ]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """One isolated trial with the cameras, recorded; the same trial without a recorder."""
    from hsqbench.sim.trial import run_isolated_trial

    path = tmp_path_factory.mktemp("rrd") / "trial.rrd"
    traces: list = []
    with RerunRecorder(path) as rec:
        with_rec = run_isolated_trial(OBJECT, SEED, recorder=rec, traces=traces)
    without = run_isolated_trial(OBJECT, SEED)
    return with_rec, without, traces[0], read_recording(path)


def test_recording_does_not_change_the_trial(recorded):
    with_rec, without, _, _ = recorded
    assert _outcomes(with_rec) == _outcomes(without)


def test_recorded_trial_has_the_documented_entities(recorded):
    result, _, _, summary = recorded
    attempt = result.attempts[0]
    paths = set(summary.entity_paths)
    expected = {
        "world",
        "world/scene",
        "world/workspace",
        "world/cloud",
        "world/cameras/left",
        "world/cameras/left/depth",
        "world/cameras/right",
        "world/cameras/right/depth",
        f"world/objects/{OBJECT}",
        "world/robot/link0",
        "world/robot/link7",
        "world/robot/hand",
        "world/robot/left_finger",
        "world/robot/right_finger",
        "world/planner/superquadrics/0",
        "world/planner/superquadrics/0/inliers",
        "plots/gripper_width",
        "events",
        "outcome",
        "scene",
    }
    assert expected <= paths, sorted(expected - paths)
    candidate_classes = {p.rsplit("/", 1)[1] for p in paths if "/candidates/" in p}
    assert candidate_classes and candidate_classes <= {"kept", *REJECTION_REASONS}
    assert ("world/planner/chosen_grasp" in paths) == (attempt.rank_executed >= 0)
    assert ("world/planner/top_grasps" in paths) == (attempt.n_grasps > 0)
    # Geometry is logged once; the collision hulls are not (configs/viewer.yaml).
    assert {"world/scene", "world/robot/link1", f"world/objects/{OBJECT}"} <= set(
        summary.static_paths
    )
    assert not any(p.endswith("/collision_geoms") for p in paths)
    # Meshes carry normals (a mesh without them is drawn unlit).
    for entity in ("world/robot/link1", "world/planner/superquadrics/0"):
        normals = _last_row(summary.path, entity, "Mesh3D:vertex_normals", None)
        assert normals is not None and len(normals) > 100
    assert str(attempt.outcome) in summary.texts["outcome"]


def test_poses_follow_sim_time(recorded):
    _, _, trace, summary = recorded
    interval = load_viewer_config().step_interval_s
    times = summary.times["sim_time"]
    for path in (f"world/objects/{OBJECT}", "world/robot/link4", "world/robot/left_finger"):
        t = times[path]
        assert t.size > 10 and np.all(np.diff(t) > 0), path
        # Poses span the whole execution, sampled every step_interval_s.
        assert t[-1] - t[0] >= trace.sim_time_s - interval
        assert np.median(np.diff(t)) == pytest.approx(interval, rel=0.01)
    # Planning results sit at the observation time, before the motion.
    assert times["world/planner/superquadrics/0"].max() < times["world/robot/link4"].max()
    assert summary.timeline("sim_time").size >= times["world/robot/link4"].size


def _last_row(path, entity: str, column: str, timeline: str | None = "sim_time"):
    """The value of ``column`` at the latest ``timeline`` time (None: of the first chunk holding
    it, for static data)."""
    from rerun.chunk import RrdReader

    best, value = -np.inf, None
    for chunk in RrdReader(path).stream():
        if chunk.entity_path.lstrip("/") != entity:
            continue
        batch = chunk.to_record_batch()
        if column not in batch.schema.names:
            continue
        if timeline is None:
            return batch.column(column).to_pylist()[-1]
        t = batch.column(timeline).cast("int64").to_numpy()
        k = int(np.argmax(t))
        if t[k] > best:
            best, value = t[k], batch.column(column).to_pylist()[k]
    return value


def test_cameras_follow_rerun_conventions(recorded):
    """Principal point at W/2, H/2 (Rerun's pixel-corner convention), optical axis toward the
    workspace, depth in metres."""
    _, _, _, summary = recorded
    path = summary.path
    lo = np.array(_last_row(path, "world/workspace", "Boxes3D:centers", None)[0])
    for cam in ("left", "right"):
        K_cols = np.array(_last_row(path, f"world/cameras/{cam}", "Pinhole:image_from_camera")[0])
        K = K_cols.reshape(3, 3).T  # stored column-major
        w, h = _last_row(path, f"world/cameras/{cam}", "Pinhole:resolution")[0]
        assert K[0, 2] == pytest.approx(w / 2) and K[1, 2] == pytest.approx(h / 2)
        R = np.array(_last_row(path, f"world/cameras/{cam}", "Transform3D:mat3x3")[0])
        R = R.reshape(3, 3).T
        t = np.array(_last_row(path, f"world/cameras/{cam}", "Transform3D:translation")[0])
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-5)
        look = (lo - t) / np.linalg.norm(lo - t)
        assert float(R[:, 2] @ look) > 0.9  # RDF: z forward, at the workspace
        assert float(R[:, 1] @ [0, 0, 1]) < 0  # y down
        meter = _last_row(path, f"world/cameras/{cam}/depth", "DepthImage:meter")
        assert meter[0] == pytest.approx(1.0 / load_viewer_config().depth_unit_m)


def test_recorded_geometry_matches_the_simulation(tmp_path):
    """Drive the recorder by hand: the logged object pose is MuJoCo's, the mesh is in the body
    frame, and the cloud and superquadrics of a plan are logged where they are."""
    from hsqbench.planner.hsq.planner import plan_grasps
    from hsqbench.sim.scene import build_scene

    model, data, info = build_scene("isolated", [OBJECT], SEED)
    path = tmp_path / "manual.rrd"
    rec = RerunRecorder(path)
    assert isinstance(rec, Recorder) and rec.enabled
    rec.on_scene(model, data, info)
    body = info.object_body_ids[OBJECT]
    # A cloud filling the object's collision hull box (the planner needs no cameras here).
    rng = np.random.default_rng(0)
    geom = info.object_geom_ids[OBJECT][0]
    centre, half = model.geom_aabb[geom, :3], model.geom_aabb[geom, 3:]
    pts = centre + rng.uniform(-1, 1, size=(600, 3)) * half
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, model.geom_quat[geom])
    pts = pts @ rot.reshape(3, 3).T + model.geom_pos[geom]  # geom frame -> body frame
    pts = pts @ data.xmat[body].reshape(3, 3).T + data.xpos[body]
    plan = plan_grasps(pts, seed=0)

    class Obs:
        points = pts
        camera_positions = np.zeros((0, 3))

    rec.on_observation(Obs())
    rec.on_plan(plan)
    start = data.xpos[body].copy()
    data.xfrc_applied[body, :] = [5.0, 0.0, 20.0, 0.0, 0.5, 0.0]  # move and turn the object
    for _ in range(50):
        mujoco.mj_step(model, data)
        rec.on_step(model, data, "test")
    rec.close()

    assert np.linalg.norm(data.xpos[body] - start) > 0.005
    got_t = np.array(_last_row(path, f"world/objects/{OBJECT}", "Transform3D:translation"))
    got_R = np.array(_last_row(path, f"world/objects/{OBJECT}", "Transform3D:mat3x3"))
    assert got_t[0] == pytest.approx(data.xpos[body], abs=1e-5)
    np.testing.assert_allclose(got_R[0].reshape(3, 3).T, data.xmat[body].reshape(3, 3), atol=1e-5)
    verts = np.array(_last_row(path, f"world/objects/{OBJECT}", "Mesh3D:vertex_positions", None))
    # The procedural box mesh: centred in x and y, base on z = 0 (object frame = body frame).
    assert verts[:, :2].mean(axis=0) == pytest.approx([0.0, 0.0], abs=1e-4)
    assert verts[:, 2].min() == pytest.approx(0.0, abs=1e-4)
    cloud = np.array(_last_row(path, "world/cloud", "Points3D:positions"))
    assert cloud == pytest.approx(pts, abs=1e-6)
    summary = read_recording(path)
    n_hidden = len(plan.hidden_superquadrics)
    assert n_hidden > 0
    assert {f"world/planner/superquadrics/{i}" for i in range(n_hidden)} <= set(
        summary.entity_paths
    )
    sq_verts = np.array(_last_row(path, "world/planner/superquadrics/0", "Mesh3D:vertex_positions"))
    assert np.abs(sq_verts.mean(axis=0) - pts.mean(axis=0)).max() < 0.05


class _Counting:
    """A recorder that counts its calls."""

    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.step_interval_s = 0.04
        self.calls: dict[str, int] = {}

    def __getattr__(self, name: str):
        if not name.startswith("on_"):
            raise AttributeError(name)

        def count(*args, **kwargs) -> None:
            self.calls[name] = self.calls.get(name, 0) + 1

        return count


def test_disabled_recorder_is_never_called():
    from hsqbench.sim.trial import load_trial_config, run_isolated_trial

    config = replace(load_trial_config(), sensor="surface")
    off = _Counting(enabled=False)
    run_isolated_trial(OBJECT, SEED, config=config, recorder=off)
    assert off.calls == {}


def test_recording_off_does_not_import_rerun():
    code = (
        "import sys; import hsqbench.sim.trial, hsqbench.cli; hsqbench.cli.build_parser(); "
        "sys.exit(int('rerun' in sys.modules))"
    )
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


# ---- the pieces --------------------------------------------------------------------------------


def test_every_rejection_reason_has_a_colour():
    assert set(REJECTION_REASONS) <= set(REASON_COLORS)


def test_score_colors_span_viridis_and_grey_for_nan():
    c = score_colors([0.0, 0.5, 1.0, np.nan, 2.0])
    assert c.dtype == np.uint8 and c.shape == (5, 4)
    assert tuple(c[0, :3]) == (68, 1, 84) and tuple(c[2, :3]) == (253, 231, 37)
    assert tuple(c[1, :3]) == (33, 145, 140)
    assert tuple(c[3]) == NO_SCORE_COLOR
    assert tuple(c[4]) == tuple(c[2])  # clipped


def test_gripper_outline_in_the_grasp_frame():
    grip = GripperModel()
    angle = 0.7
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]]
    )
    p = np.array([0.4, -0.1, 0.2])
    width = 0.05
    strips = gripper_outline(grip, p, R, width, 0.05)
    assert len(strips) == 5
    local = [(s - p) @ R for s in strips]  # back to the grasp frame
    right, left, palm, stem, closing = local
    assert np.allclose(np.concatenate(local)[:, 1], 0.0)  # in the closing-approach plane
    assert right[:, 0].min() == pytest.approx(width / 2)
    assert right[:, 0].max() == pytest.approx(width / 2 + grip.finger_thickness_m)
    assert left[:, 0].max() == pytest.approx(-width / 2)
    assert right[:, 2].max() == pytest.approx(grip.fingertip_overhang_m)
    assert palm[:, 2].max() == pytest.approx(-grip.jaw_length_m)
    assert palm[:, 0].max() - palm[:, 0].min() == pytest.approx(grip.palm_width_m)
    assert stem[:, 2].max() <= palm[:, 2].min() + 1e-12  # the stem is behind the palm
    assert closing[:, 0] == pytest.approx([-width / 2, width / 2])
    with pytest.raises(ValueError, match="opening_m"):
        gripper_outline(grip, p, R, float("nan"), 0.05)


def _spec_model() -> mujoco.MjModel:
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="b", pos=[1.0, 0.0, 0.0])
    body.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[0.1, 0.2, 0.3],
        pos=[0.0, 0.5, 0.0],
        rgba=[1.0, 0.0, 0.0, 1.0],
    )
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0], group=3)
    # A finely tessellated sphere as a mesh geom (many faces, MuJoCo-duplicated vertices).
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=4, radius=0.1)
    spec.add_mesh(name="ball", uservert=sphere.vertices.ravel(), userface=sphere.faces.ravel())
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_MESH, meshname="ball", pos=[0.0, 0.0, 1.0])
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[1, 1, 0.1])
    return spec.compile()


def test_body_meshes_in_the_body_frame_with_groups_and_decimation():
    model = _spec_model()
    meshes = body_meshes(model, groups=(0, 1, 2), max_faces_per_geom=200)
    assert set(meshes) == {1}  # the plane is skipped, body 0 has nothing else
    m = meshes[1]
    box = m.vertices[(m.colors[:, 0] == 255) & (m.colors[:, 1] == 0)]
    assert box.min(axis=0) == pytest.approx([-0.1, 0.3, -0.3], abs=1e-6)
    assert box.max(axis=0) == pytest.approx([0.1, 0.7, 0.3], abs=1e-6)
    ball_mask = m.vertices[:, 2] > 0.5
    ball = m.vertices[ball_mask]
    assert np.linalg.norm(ball - [0, 0, 1], axis=1) == pytest.approx(0.1, abs=0.01)
    # Normals: the box's are its face directions (flat shading), the ball's point outward.
    box_n = m.normals[(m.colors[:, 0] == 255) & (m.colors[:, 1] == 0)]
    assert np.sort(np.abs(box_n), axis=1)[:, :2] == pytest.approx(0.0, abs=1e-6)
    radial = (ball - [0, 0, 1]) / np.linalg.norm(ball - [0, 0, 1], axis=1, keepdims=True)
    assert np.einsum("ij,ij->i", m.normals[ball_mask], radial).min() > 0.95
    assert m.n_faces <= 12 + 200  # the 1280-face sphere decimated
    assert m.faces.max() < len(m.vertices)
    hulls = body_meshes(model, groups=(3,))
    assert set(hulls) == {1} and hulls[1].vertices.max() < 0.06  # only the small sphere


def test_viewer_config_rejects_bad_values():
    with pytest.raises(ValueError, match="step_interval_s"):
        ViewerConfig(step_interval_s=0.0)
    with pytest.raises(ValueError, match="cloud_radius_m"):
        ViewerConfig(cloud_radius_m=-1.0)


def test_recorder_needs_an_rrd_path(tmp_path):
    with pytest.raises(ValueError, match=r"\.rrd"):
        RerunRecorder(tmp_path / "out.txt")
