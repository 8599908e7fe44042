"""The baseline planners (single-sq, antipodal) in the harness: known shapes on a table, two views."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from hsqbench.config import from_dict, load_config, to_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.api import Planner, PlanningContext
from hsqbench.planner.baselines.antipodal import AntipodalPlanner, plan_antipodal
from hsqbench.planner.baselines.config import (
    AntipodalConfig,
    BaselinesConfig,
    load_baselines_config,
)
from hsqbench.planner.baselines.single_sq import SingleSQPlanner, plan_single_sq
from hsqbench.planner.cleaning import clean_cloud
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import resolve_config
from hsqbench.planner.hsq.planner import plan_grasps
from hsqbench.planner.hsq.stage_two.candidates import CandidateSet
from hsqbench.planner.hsq.stage_two.elimination import eliminate, unobservable_contacts
from hsqbench.planner.hsq.stage_two.hidden_bodies import body_obstacles
from hsqbench.planner.registry import get_planner
from hsqbench.superquadric.fit import point_to_surface_alpha
from tests.shapes import Box, l_of_two_boxes, union_cloud, visible_mask

TABLE = (0.0, 0.0, 1.0, 0.0)
GRIPPER = GripperModel()
#: Two cameras on opposite sides of the table, 45 degrees up: together they see every side.
CAMERAS = np.array([[-0.45, -0.45, 0.55], [0.45, 0.45, 0.55]])
CONE_DEG = AntipodalConfig().friction_half_angle_deg


def two_views(points: np.ndarray, normals: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The surface points both cameras see, with 1 mm Gaussian noise (metres)."""
    mask = np.zeros(len(points), dtype=bool)
    for camera in CAMERAS:
        mask |= visible_mask(points, normals, camera)
    return points[mask] + rng.normal(scale=0.001, size=(int(mask.sum()), 3))


def seen(parts, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    cloud = union_cloud(tuple(parts), 0.0025, rng)
    return two_views(cloud.points, cloud.normals, rng)


def yawed_box(yaw_deg: float) -> Box:
    """A 6 x 4 x 10 cm box standing on the table."""
    rot = Rotation.from_euler("z", yaw_deg, degrees=True).as_matrix()
    return Box((0.03, 0.02, 0.05), rot, np.array([0.4, -0.1, 0.05]))


def gripper_corners(grasp, approach_distance: float = 0.05) -> np.ndarray:
    """World corners of the open fingers and the swept palm of a grasp, (24, 3)."""
    boxes = GRIPPER.boxes(palm_extension_m=approach_distance)
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    local = np.concatenate([box[pick, [0, 1, 2]] for box in boxes])
    return grasp.position + local @ grasp.rotation.T


def arrays(result) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (G, 3), closing axes (G, 3) and widths (G,) of a result's grasps."""
    grasps = list(result.grasps)
    return (
        np.array([g.position for g in grasps]),
        np.array([g.closing_axis for g in grasps]),
        np.array([g.width for g in grasps]),
    )


# ----------------------------------------------------------------------------- registry
@pytest.mark.parametrize(
    ("name", "cls"), [("single-sq", SingleSQPlanner), ("antipodal", AntipodalPlanner)]
)
def test_registry_builds_the_baselines(name, cls) -> None:
    planner = get_planner(name)
    assert isinstance(planner, cls) and isinstance(planner, Planner)
    assert planner.name == name


def test_unknown_planner_error_lists_all_three() -> None:
    with pytest.raises(ValueError, match="unknown planner 'gpd'") as info:
        get_planner("gpd")
    for name in ("hsq", "single-sq", "antipodal"):
        assert name in str(info.value)


# ----------------------------------------------------------------------------- config
def test_yaml_mirrors_the_dataclass_defaults() -> None:
    assert to_dict(load_baselines_config()) == to_dict(BaselinesConfig())


@pytest.mark.parametrize(
    ("override", "needle"),
    [
        ({"friction_half_angle_deg": 95.0}, "friction_half_angle_deg"),
        ({"roll_step_deg": 25.0}, "divide 360"),
        ({"normal_neighbours": 2}, "normal_neighbours"),
        ({"n_samples": 0}, "n_samples"),
        ({"ray_radius": 0.003}, "unknown key"),
    ],
)
def test_bad_settings_are_refused_by_name(override, needle) -> None:
    with pytest.raises(ConfigError, match=needle):
        from_dict(BaselinesConfig, {"antipodal": override})


def test_a_planner_config_object_is_refused_with_a_hint() -> None:
    from hsqbench.planner.hsq.config import PlannerConfig

    with pytest.raises(TypeError, match="'planner' entry"):
        get_planner("antipodal", PlannerConfig())


def test_a_config_path_is_accepted(tmp_path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text("antipodal:\n  n_samples: 50\n")
    planner = AntipodalPlanner(path)
    assert planner.config.antipodal.n_samples == 50
    assert load_config(BaselinesConfig, path).antipodal.voxel_m == AntipodalConfig().voxel_m


# ----------------------------------------------------------------------------- single-sq
def test_single_sq_grasps_a_box_across_its_narrow_faces() -> None:
    box = yawed_box(-40.0)
    points = seen([box], seed=3)
    result = get_planner("single-sq").plan(points, PlanningContext(support_plane=TABLE, seed=0))
    assert result.planner == "single-sq"
    assert result.grasps, result.reason
    assert len(result.hidden_superquadrics) == 1
    hidden = result.hidden_superquadrics[0]
    # One superquadric describes a box: nearly every point is its inlier.
    assert hidden.inliers.size > 0.97 * len(points)
    positions, closing, widths = arrays(result)
    # Across the 6 cm (box x) or 4 cm (box y) faces, horizontally, never along the 10 cm height.
    across = np.max(np.abs(closing @ box.rotation[:, :2]), axis=1)
    assert np.all(across > 0.97)
    assert np.all(widths < GRIPPER.max_opening_m)
    assert np.all(box.contains(positions, tol=0.002))
    assert all(np.all(gripper_corners(g)[:, 2] >= 0.0) for g in result.grasps)
    assert set(result.timings) >= {"recovery", "elimination", "scoring", "total"}


def test_single_sq_describes_an_l_worse_than_the_hidden_superquadrics() -> None:
    rot = Rotation.from_euler("z", 30.0, degrees=True).as_matrix()
    parts = l_of_two_boxes(rot, np.array([0.3, 0.1, 0.0]))
    points = seen(parts, seed=2)
    single = plan_single_sq(points, support_plane=TABLE, seed=0)
    hsq = plan_grasps(points, support_plane=TABLE, seed=0)
    one = single.hidden_superquadrics[0]
    hidden = hsq.hidden_superquadrics
    # The one superquadric envelops both boxes (a 12 x 12 cm block); the inner faces of the L
    # are its outliers, and its own inliers lie farther from its surface than any hidden one's.
    assert one.inliers.size < 0.9 * len(points)
    assert one.alpha > min(h.alpha for h in hidden)
    # Over the whole cloud: mean distance to the single surface vs. to the nearest hidden one.
    nearest_hidden = cKDTree(
        np.concatenate([h.superquadric.sample_surface(0.002)[0] for h in hidden])
    ).query(points)[0]
    assert point_to_surface_alpha(points, one.superquadric, 0.002) > 2.0 * nearest_hidden.mean()
    # Much of its surface is air: coverage, and with it every score, stays low.
    assert one.beta < 0.6 < max(h.beta for h in hidden)
    best_single = single.best.score if single.best else 0.0
    assert best_single < 0.5 * hsq.best.score


def two_boxes_apart() -> tuple[Box, Box, np.ndarray]:
    """Two 6 x 4 x 10 cm boxes with footprints 3 cm apart (a packed scene's 2 cm or more), seen
    by both cameras, plus three stray points between them."""
    a = Box((0.03, 0.02, 0.05), np.eye(3), np.array([0.40, -0.05, 0.05]))
    b = Box((0.03, 0.02, 0.05), np.eye(3), np.array([0.40, 0.02, 0.05]))
    strays = np.array([[0.40, -0.015, 0.02], [0.40, -0.015, 0.05], [0.39, -0.015, 0.08]])
    return a, b, np.concatenate([seen([a], seed=4), seen([b], seed=5), strays])


def test_single_sq_fits_one_superquadric_per_object_in_packed_scenes() -> None:
    a, b, points = two_boxes_apart()
    packed = plan_single_sq(points, packed=True, support_plane=TABLE, seed=0)
    assert len(packed.hidden_superquadrics) == 2 and packed.grasps, packed.reason
    positions = np.array([g.position for g in packed.grasps])
    inside = a.contains(positions, tol=0.002) | b.contains(positions, tol=0.002)
    assert inside.all()
    assert a.contains(positions, tol=0.002).any() and b.contains(positions, tol=0.002).any()
    # Isolated, the same cloud is one object: one superquadric around both boxes.
    whole = plan_single_sq(points, packed=False, support_plane=TABLE, seed=0)
    assert len(whole.hidden_superquadrics) == 1
    assert whole.hidden_superquadrics[0].superquadric.scale.max() > 0.05


# ----------------------------------------------------------------------------- antipodal
@pytest.mark.parametrize(("yaw", "seed"), [(25.0, 1), (10.0, 0)])
def test_antipodal_box_grasps_close_across_opposite_faces(yaw, seed) -> None:
    box = yawed_box(yaw)
    points = seen([box], seed=seed)
    result = get_planner("antipodal").plan(points, PlanningContext(support_plane=TABLE, seed=seed))
    assert result.planner == "antipodal"
    assert result.grasps, result.reason
    positions, closing, widths = arrays(result)
    # The closing axis joins a pair of opposite side faces: within the friction cone of the
    # estimated normals, which are a few degrees off the true ones (10 deg of slack).
    angle = np.degrees(np.arccos(np.max(np.abs(closing @ box.rotation[:, :2]), axis=1)))
    assert np.all(angle < CONE_DEG + 10.0), angle.max()
    assert np.median(angle) < 10.0
    # Widths along the faces' normal are the 4 or 6 cm between those faces (plus noise; the
    # cone's tilt lengthens the width itself by 1 / cos(angle)).
    gap = widths * np.cos(np.radians(angle))
    assert np.all(((gap > 0.035) & (gap < 0.047)) | ((gap > 0.055) & (gap < 0.07)))
    assert np.all(box.contains(positions, tol=0.002))
    assert all(np.all(gripper_corners(g)[:, 2] >= 0.0) for g in result.grasps)
    # The table rule did remove poses (roll angles that reach below the box's base).
    assert result.removed_by["table"] > 0
    scores = np.array([g.score for g in result.grasps])
    assert np.all(np.diff(scores) <= 0.0) and np.all((scores > 0.0) & (scores <= 1.0))
    assert set(result.grasps[0].factors) == {"h_antipodal", "h_delta"}


def test_antipodal_finds_nothing_on_a_ball_wider_than_the_opening() -> None:
    rng = np.random.default_rng(4)
    centre = np.array([0.1, 0.2, 0.05])
    normals = rng.normal(size=(12_000, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    points = two_views(centre + 0.05 * normals, normals, rng)
    result = plan_antipodal(points, support_plane=TABLE, seed=0)
    assert len(result.grasps) == 0
    assert "antipodal pairs" in result.reason
    assert "are wider than the 0.08 m opening" in result.reason
    assert result.remaining["width"] == 0 < result.removed_by["width"]
    # The pairs found are diameters of the ball.
    widths = 2.0 * result.candidates.lines.half_lengths
    assert np.all(widths > 0.09)


def test_antipodal_reason_when_no_ray_finds_a_partner() -> None:
    # A single flat patch: every inward ray leaves the cloud.
    rng = np.random.default_rng(0)
    patch = np.column_stack([rng.uniform(0, 0.05, (2000, 2)), np.full(2000, 0.02)])
    result = plan_antipodal(patch, support_plane=TABLE, seed=0)
    assert len(result.grasps) == 0
    assert "none of the" in result.reason and "antipodal partner" in result.reason


def test_antipodal_is_deterministic_per_seed() -> None:
    points = seen([yawed_box(60.0)], seed=5)
    a = plan_antipodal(points, support_plane=TABLE, seed=7)
    b = AntipodalPlanner().plan(points, PlanningContext(support_plane=TABLE, seed=7))
    c = plan_antipodal(points, support_plane=TABLE, seed=8)
    for name in ("centres", "directions", "approach0", "half_lengths"):
        np.testing.assert_array_equal(
            getattr(a.candidates.lines, name), getattr(b.candidates.lines, name)
        )
    np.testing.assert_array_equal(a.candidates.scores, b.candidates.scores)
    assert [g.to_dict() for g in a.grasps[:20]] == [g.to_dict() for g in b.grasps[:20]]
    # Another seed samples other points.
    assert not np.array_equal(a.candidates.lines.centres, c.candidates.lines.centres)


@pytest.mark.parametrize("name", ["single-sq", "antipodal"])
def test_results_serialise_to_json(name) -> None:
    points = seen([yawed_box(45.0)], seed=4)
    result = get_planner(name).plan(points, PlanningContext(support_plane=TABLE))
    out = json.loads(json.dumps(result.to_dict(top=3)))
    assert out["planner"] == name and out["n_grasps"] == len(result.grasps) > 0
    assert len(out["grasps"]) == 3 and out["grasps"][0]["family"]
    assert len(out["hidden_superquadrics"]) == (1 if name == "single-sq" else 0)


def test_single_sq_is_deterministic() -> None:
    points = seen([yawed_box(15.0)], seed=6)
    a = plan_single_sq(points, support_plane=TABLE, seed=3)
    b = plan_single_sq(points, support_plane=TABLE, seed=3)
    np.testing.assert_array_equal(a.candidates.scores, b.candidates.scores)
    assert [g.to_dict() for g in a.grasps[:20]] == [g.to_dict() for g in b.grasps[:20]]


def test_packed_scenes_drop_the_centroid_factor() -> None:
    points = seen([yawed_box(35.0)], seed=1)
    loose = plan_antipodal(points, support_plane=TABLE, seed=0)
    packed = AntipodalPlanner().plan(points, PlanningContext(support_plane=TABLE, packed=True))
    assert "h_delta" in loose.grasps[0].factors and "h_delta" not in packed.grasps[0].factors
    assert len(packed.grasps) == len(loose.grasps)
    single = plan_single_sq(points, support_plane=TABLE, packed=True)
    assert "h_delta" not in single.grasps[0].factors


def test_without_a_table_roll_zero_still_approaches_from_above() -> None:
    points = seen([yawed_box(20.0)], seed=2)
    result = plan_antipodal(points, seed=0)
    lines = result.candidates.lines
    # approach0 is world -z made perpendicular to each closing line (exactly its projection).
    down = np.array([0.0, 0.0, -1.0])
    expected = down - (lines.directions @ down)[:, None] * lines.directions
    expected /= np.linalg.norm(expected, axis=1, keepdims=True)
    np.testing.assert_allclose(lines.approach0, expected, atol=1e-9)
    # The box's faces are vertical: lines tilt at most the friction cone plus the normals'
    # error (10 deg, as above), so approach0 points well down.
    assert np.all(lines.approach0[:, 2] < -np.cos(np.deg2rad(CONE_DEG + 10.0)))
    assert result.remaining["table"] == result.remaining["support"]


@pytest.mark.parametrize("planner", ["single-sq", "antipodal"])
@pytest.mark.parametrize(
    ("points", "needle"),
    [
        (np.zeros((0, 3)), "empty"),
        (np.array([[0.0, 0.0, np.nan]] * 30), "NaN"),
        (np.zeros((10, 2)), r"\(N, 3\)"),
    ],
)
def test_bad_clouds_are_refused(planner, points, needle) -> None:
    with pytest.raises(ValueError, match=needle):
        get_planner(planner).plan(points, PlanningContext())


def test_antipodal_refuses_a_cloud_too_small_for_normals() -> None:
    tiny = np.random.default_rng(0).uniform(0.0, 0.005, size=(50, 3))
    with pytest.raises(ValueError, match="neighbours of a normal"):
        plan_antipodal(tiny)


def test_settings_reach_the_sampler() -> None:
    points = seen([yawed_box(25.0)], seed=1)
    cfg = BaselinesConfig()
    few = dataclasses.replace(cfg, antipodal=dataclasses.replace(cfg.antipodal, n_samples=40))
    result = plan_antipodal(points, few, support_plane=TABLE, seed=0)
    assert 0 < len(result.candidates.lines) <= 40
    assert result.candidates.n_roll == round(360.0 / cfg.antipodal.roll_step_deg)


# ----------------------------------------------------------------------------- fairness with hsq
PLAN_FUNCTIONS = {"single-sq": plan_single_sq, "antipodal": plan_antipodal}


def _fresh_elimination(result, points: np.ndarray, cameras=None):
    """The result's closing lines through the shared elimination again, on ``points``."""
    grasp_cfg = resolve_config(BaselinesConfig().planner).grasp
    if result.planner == "antipodal":
        grasp_cfg = dataclasses.replace(grasp_cfg, roll_step_deg=AntipodalConfig().roll_step_deg)
    cands = CandidateSet(result.candidates.lines, result.candidates.roll_angles)
    eliminate(cands, points, GRIPPER, grasp_cfg, np.asarray(TABLE), 0, camera_positions=cameras)
    return cands


@pytest.mark.parametrize("name", ["single-sq", "antipodal"])
def test_a_flying_pixel_in_a_finger_path_no_longer_removes_a_baseline_grasp(name) -> None:
    cleaning = resolve_config(BaselinesConfig().planner).cleaning
    points = seen([yawed_box(30.0)], seed=3)
    plan = PLAN_FUNCTIONS[name]
    clean = plan(points, support_plane=TABLE, seed=0)
    best = clean.best
    assert best is not None, clean.reason
    # A flying pixel inside the best grasp's +x finger, 1.5 cm up from the closing line.
    local = np.array([best.approach_width / 2 + GRIPPER.finger_thickness_m / 2, 0.0, -0.015])
    pixel = best.position + best.rotation @ local
    alone = cKDTree(points).query_ball_point(pixel, cleaning.radius_m, return_length=True)
    assert alone < cleaning.min_neighbours  # isolated: what cleaning removes
    noisy = np.vstack([points, pixel])
    # The pixel would remove the grasp if it reached the shared elimination ...
    top = int(np.nanargmax(clean.candidates.scores))
    assert _fresh_elimination(clean, noisy).rejected_by[top] in ("collision", "sweep")
    # ... but the baseline cleans it away, as hsq does: the same grasps as without it.
    result = get_planner(name).plan(noisy, PlanningContext(support_plane=TABLE, seed=0))
    assert result.n_removed >= 1 and "cleaning" in result.timings
    assert [g.to_dict() for g in result.grasps[:20]] == [g.to_dict() for g in clean.grasps[:20]]


@pytest.mark.parametrize("name", ["single-sq", "antipodal"])
def test_camera_positions_waive_support_for_the_baselines_as_for_hsq(name) -> None:
    points = seen([yawed_box(20.0)], seed=2)
    planner = get_planner(name)
    # The waiver alone: with the cameras, single-sq's superquadric also gives rule 6's hidden
    # bodies, which replace the facing test (test_single_sq_runs_the_hidden_body_rule).
    pcfg = planner.planner_config
    planner.planner_config = dataclasses.replace(
        pcfg, grasp=dataclasses.replace(pcfg.grasp, body_rule=False)
    )
    blind = planner.plan(points, PlanningContext(support_plane=TABLE, seed=0))
    context = PlanningContext(support_plane=TABLE, seed=0, camera_positions=CAMERAS[:1])
    seeing = planner.plan(points, context)
    before, after = blind.candidates.rejected_by, seeing.candidates.rejected_by
    assert len(before) == len(after)  # the same candidates: only the rules' verdicts differ
    rescued = np.flatnonzero((before == "support") & (after != "support"))
    assert rescued.size > 0 and len(seeing.grasps) > len(blind.grasps)
    assert np.all(after[before != "support"] == before[before != "support"])
    # Each rescued pose has a contact facing away from the camera (the hsq planner's rule) ...
    lines = np.unique(seeing.candidates.line_index[rescued])
    grasp_cfg = resolve_config(BaselinesConfig().planner).grasp
    unseen = unobservable_contacts(
        seeing.candidates, lines, CAMERAS[:1], grasp_cfg, np.asarray(TABLE)
    )
    assert np.all(unseen.any(axis=1))
    # ... and the verdicts are the shared elimination's with those cameras.
    cloud = clean_cloud(points, resolve_config(BaselinesConfig().planner).cleaning).points
    again = _fresh_elimination(seeing, cloud, CAMERAS[:1])
    np.testing.assert_array_equal(again.rejected_by, after)


def test_single_sq_runs_the_hidden_body_rule_with_the_cameras_and_antipodal_does_not() -> None:
    points = seen([yawed_box(20.0)], seed=2)
    context = PlanningContext(support_plane=TABLE, seed=0, camera_positions=CAMERAS[:1])
    single = get_planner("single-sq").plan(points, context)
    grasp_cfg = resolve_config(BaselinesConfig().planner).grasp
    cloud = clean_cloud(points, resolve_config(BaselinesConfig().planner).cleaning).points
    sqs = [h.superquadric for h in single.hidden_superquadrics]
    bodies = body_obstacles(sqs, cloud, grasp_cfg, CAMERAS[:1], np.asarray(TABLE))
    assert len(bodies) > 0
    cands = CandidateSet(single.candidates.lines, single.candidates.roll_angles)
    eliminate(cands, cloud, GRIPPER, grasp_cfg, np.asarray(TABLE), 0, None, CAMERAS[:1], bodies)
    np.testing.assert_array_equal(cands.rejected_by, single.candidates.rejected_by)
    plain = CandidateSet(single.candidates.lines, single.candidates.roll_angles)
    eliminate(plain, cloud, GRIPPER, grasp_cfg, np.asarray(TABLE), 0, None, CAMERAS[:1])
    assert not np.array_equal(plain.rejected_by, single.candidates.rejected_by)
    # The antipodal sampler has no superquadric: its verdicts are the rules without rule 6.
    antipodal = get_planner("antipodal").plan(points, context)
    assert "hidden" not in set(antipodal.candidates.rejected_by)
    again = _fresh_elimination(
        antipodal,
        clean_cloud(points, resolve_config(BaselinesConfig().planner).cleaning).points,
        CAMERAS[:1],
    )
    np.testing.assert_array_equal(again.rejected_by, antipodal.candidates.rejected_by)


@pytest.mark.parametrize("name", ["single-sq", "antipodal"])
def test_a_cloud_cleaning_empties_gets_the_hsq_planners_answer(name) -> None:
    sparse = np.stack(np.meshgrid(*[np.arange(4) * 0.05] * 3), axis=-1).reshape(-1, 3)
    result = get_planner(name).plan(sparse, PlanningContext(support_plane=TABLE))
    hsq = plan_grasps(sparse, support_plane=TABLE)
    assert len(result.grasps) == 0 and result.n_removed == len(sparse) == hsq.n_removed
    assert result.reason == hsq.reason and result.reason.startswith("cleaning removed all 64")
    assert result.planner == name
