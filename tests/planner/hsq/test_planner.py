"""The hsq planner (hsqbench.planner.hsq.planner) end to end: known shapes on a table, seen by two
side cameras."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.api import PlanningContext, PlanResult
from hsqbench.planner.grasp import Grasp
from hsqbench.planner.gripper import GripperModel
from hsqbench.planner.hsq.config import PlannerConfig
from hsqbench.planner.hsq.planner import HSQPlanner, plan_grasps, redraw_seed
from hsqbench.planner.hsq.stage_two.plan import plan_from_hidden
from hsqbench.superquadric.fit import alpha_beta
from hsqbench.superquadric.geometry import Superquadric
from tests.shapes import Box, Cylinder, mug_with_handle, union_cloud, visible_mask

TABLE = (0.0, 0.0, 1.0, 0.0)
GRIPPER = GripperModel()
#: Two cameras on opposite sides of the table, 45 degrees up: together they see every side.
CAMERAS = np.array([[-0.45, -0.45, 0.55], [0.45, 0.45, 0.55]])


@dataclass
class Hidden:
    """A ground-truth hidden superquadric with the paper's alpha and beta on its points."""

    superquadric: Superquadric
    inliers: np.ndarray
    alpha: float
    beta: float


def seen(parts, seed: int = 0, spacing: float = 0.0025, noise: float = 0.001) -> np.ndarray:
    """What the two cameras see of a union of primitives, with Gaussian noise (metres)."""
    rng = np.random.default_rng(seed)
    cloud = union_cloud(tuple(parts), spacing, rng)
    mask = np.zeros(len(cloud.points), dtype=bool)
    for camera in CAMERAS:
        mask |= visible_mask(cloud.points, cloud.normals, camera)
    points = cloud.points[mask]
    return points + rng.normal(scale=noise, size=points.shape)


def hidden(sq: Superquadric, points: np.ndarray) -> Hidden:
    inliers = np.flatnonzero(sq.radial_distance(points) < 0.005)
    alpha, beta = alpha_beta(points[inliers], sq, 0.002, 0.004)
    return Hidden(sq, inliers, alpha, beta)


def gripper_corners(grasp, approach_distance: float = 0.05) -> np.ndarray:
    """World corners of the fingers (open) and the swept palm of a grasp, (24, 3)."""
    boxes = GRIPPER.boxes(palm_extension_m=approach_distance)
    pick = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)])
    local = np.concatenate([box[pick, [0, 1, 2]] for box in boxes])
    return grasp.position + local @ grasp.rotation.T


def finger_samples(grasp, n: int = 6) -> np.ndarray:
    """Points filling both fingers at the grasp's contact width, world frame."""
    boxes = GRIPPER.boxes(opening_m=grasp.width)[:2]
    t = (np.arange(n) + 0.5) / n
    g = np.stack(np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
    local = np.concatenate([lo + g * (hi - lo) for lo, hi in boxes])
    return grasp.position + local @ grasp.rotation.T


def yawed_box(yaw_deg: float) -> Box:
    rot = Rotation.from_euler("z", yaw_deg, degrees=True).as_matrix()
    return Box((0.03, 0.02, 0.05), rot, np.array([0.4, -0.1, 0.05]))


def check_box_result(result: PlanResult, box: Box) -> None:
    assert result.grasps, result.reason
    top = result.grasps[0]
    closing = top.closing_axis
    # Across the 6 cm (box x) or 4 cm (box y) faces, horizontally.
    assert max(abs(closing @ box.rotation[:, 0]), abs(closing @ box.rotation[:, 1])) > 0.97
    assert top.width < GRIPPER.max_opening_m
    assert box.contains(top.position[None])[0]
    for grasp in result.grasps:
        assert np.all(gripper_corners(grasp)[:, 2] >= 0.0)


def test_box_on_a_table_with_its_true_superquadric() -> None:
    box = yawed_box(25.0)
    points = seen([box])
    sq = Superquadric(0.1, 0.1, box.half_extents, box.rotation, box.center)
    result = plan_from_hidden(points, [hidden(sq, points)], support_plane=TABLE)
    check_box_result(result, box)
    assert result.grasps[0].width == pytest.approx(0.04, abs=1e-3) or result.grasps[
        0
    ].width == pytest.approx(0.06, abs=1e-3)
    assert result.remaining["table"] < result.remaining["support"]  # the table did remove some


def test_box_on_a_table_end_to_end() -> None:
    box = yawed_box(-40.0)
    points = seen([box], seed=3)
    result = plan_grasps(points, support_plane=TABLE, seed=0)
    check_box_result(result, box)
    assert set(result.timings) == {
        "cleaning",
        "recovery",
        "synthesis",
        "elimination",
        "scoring",
        "total",
    }
    assert result.hidden_superquadrics and result.candidates is not None


def test_cylinder_is_grasped_at_many_rotations_about_its_axis() -> None:
    cyl = Cylinder(0.03, 0.05, center=np.array([0.0, 0.3, 0.05]))
    points = seen([cyl], seed=1)
    sq = Superquadric(0.1, 1.0, [0.03, 0.03, 0.05], translation=cyl.center)
    result = plan_from_hidden(points, [hidden(sq, points)], support_plane=TABLE)
    closing = np.array([g.closing_axis for g in result.grasps])
    side = np.abs(closing[:, 2]) < 0.05
    angles = np.round(np.mod(np.degrees(np.arctan2(closing[side, 1], closing[side, 0])), 180.0))
    assert len(set(angles)) >= 6, sorted(set(angles))


def test_wide_sphere_gets_no_grasp_and_the_reason_says_why() -> None:
    points = seen([Cylinder(0.05, 0.05, center=np.array([0.0, 0.0, 0.05]))])  # any cloud
    sphere = Superquadric(1.0, 1.0, [0.05, 0.05, 0.05], translation=[0.0, 0.0, 0.05])
    result = plan_from_hidden(points, [hidden(sphere, points)], support_plane=TABLE)
    assert len(result.grasps) == 0
    assert "wider than the 0.08 m opening" in result.reason
    assert result.removed_by["width"] == len(result.candidates)


def test_mug_is_grasped_by_its_handle_not_through_its_body() -> None:
    body, handle = mug_with_handle(translation=np.array([0.3, 0.0, 0.0]))
    points = seen([body, handle], seed=2)
    sqs = [
        Superquadric(
            0.1, 1.0, [body.radius, body.radius, body.half_height], body.rotation, body.center
        ),
        Superquadric(0.1, 0.1, handle.half_extents, handle.rotation, handle.center),
    ]
    result = plan_from_hidden(points, [hidden(s, points) for s in sqs], support_plane=TABLE)
    assert result.grasps, result.reason
    assert {g.source for g in result.grasps} == {1}  # the 8 cm body is too wide
    for grasp in result.grasps:
        assert handle.contains(grasp.position[None], tol=0.002)[0]
        assert not np.any(body.contains(finger_samples(grasp)))
    # The handle is 1.6 cm thick: closing across it; across its 3.5 cm length the inner finger
    # would be inside the body.
    assert all(abs(g.closing_axis @ handle.rotation[:, 1]) > 0.97 for g in result.grasps)


@dataclass(frozen=True)
class Sphere:
    """A sphere for tests.shapes.union_cloud: radius (m) and centre (m)."""

    radius: float
    center: np.ndarray

    def area(self) -> float:
        return 4.0 * np.pi * self.radius**2

    def sample_surface(self, n: int, rng: np.random.Generator):
        d = rng.normal(size=(n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        return self.center + self.radius * d, d

    def contains(self, points, tol: float = 1e-6) -> np.ndarray:
        return np.linalg.norm(np.asarray(points) - self.center, axis=1) <= self.radius + tol


def test_wide_sphere_end_to_end_gets_no_grasp_and_a_reason() -> None:
    points = seen([Sphere(0.05, np.array([0.5, 0.0, 0.05]))], seed=1)
    result = plan_grasps(points, support_plane=TABLE, seed=1)
    assert len(result.grasps) == 0
    assert result.reason.startswith("no candidate survived") or "wider than" in result.reason
    assert result.removed_by["width"] > 0


def test_cylinder_end_to_end_is_grasped_at_many_rotations() -> None:
    points = seen([Cylinder(0.03, 0.05, center=np.array([0.5, 0.0, 0.05]))], seed=2)
    result = plan_grasps(points, support_plane=TABLE, seed=2)
    closing = np.array([g.closing_axis for g in result.grasps])
    side = np.abs(closing[:, 2]) < 0.05
    angles = np.round(np.mod(np.degrees(np.arctan2(closing[side, 1], closing[side, 0])), 180.0))
    assert len(set(angles)) >= 5, sorted(set(angles))


def test_mug_end_to_end_grasps_handle_or_wall_never_inside_the_body() -> None:
    body, handle = mug_with_handle(translation=np.array([0.5, 0.0, 0.0]))
    points = seen([body, handle], seed=0)
    result = plan_grasps(points, support_plane=TABLE, seed=0)
    assert result.grasps, result.reason
    for grasp in result.grasps:
        on_handle = handle.contains(grasp.position[None], tol=0.003)[0]
        radial = np.hypot(*(grasp.position[:2] - body.center[:2]))
        on_wall = abs(radial - body.radius) < 0.01
        assert on_handle or on_wall
        # The fingers, open to the approach width, are never inside the body.
        boxes = GRIPPER.boxes(opening_m=grasp.approach_width)[:2]
        t = (np.arange(5) + 0.5) / 5
        g = np.stack(np.meshgrid(t, t, t, indexing="ij"), axis=-1).reshape(-1, 3)
        local = np.concatenate([lo + g * (hi - lo) for lo, hi in boxes])
        assert not np.any(body.contains(grasp.position + local @ grasp.rotation.T))


def test_packed_scenes_drop_the_centroid_factor() -> None:
    box = yawed_box(10.0)
    points = seen([box])
    h = hidden(Superquadric(0.1, 0.1, box.half_extents, box.rotation, box.center), points)
    loose = plan_from_hidden(points, [h], support_plane=TABLE)
    packed = plan_from_hidden(points, [h], support_plane=TABLE, packed=True)
    assert "h_delta" in loose.grasps[0].factors and "h_delta" not in packed.grasps[0].factors
    assert len(packed.grasps) == len(loose.grasps)


def test_result_is_reproducible_and_serialisable() -> None:
    box = yawed_box(60.0)
    points = seen([box], seed=5)
    a = plan_grasps(points, support_plane=TABLE, seed=4)
    b = plan_grasps(points, support_plane=TABLE, seed=4)
    np.testing.assert_array_equal(a.candidates.rejected_by, b.candidates.rejected_by)
    np.testing.assert_array_equal(a.candidates.scores, b.candidates.scores)
    out = a.to_dict(top=3)
    assert len(out["grasps"]) == min(3, len(a.grasps)) and out["n_grasps"] == len(a.grasps)
    assert list(out["remaining"]) == [
        "synthesised",
        "duplicate",
        "width",
        "support",
        "table",
        "collision",
        "sweep",
        "hidden",
    ]


@pytest.mark.parametrize(
    ("points", "needle"),
    [
        (np.zeros((0, 3)), "empty"),
        (np.array([[0.0, 0.0, np.nan]] * 20), "NaN"),
        (np.zeros((10, 2)), r"\(N, 3\)"),
    ],
)
def test_bad_clouds_are_refused(points, needle) -> None:
    with pytest.raises(ValueError, match=needle):
        plan_grasps(points)


def test_hsq_planner_uses_the_context() -> None:
    box = yawed_box(30.0)
    points = seen([box], seed=6)
    planner = HSQPlanner()
    result = planner.plan(points, PlanningContext(support_plane=TABLE, packed=True, seed=1))
    assert result.grasps and "h_delta" not in result.grasps[0].factors
    for grasp in result.grasps:
        assert np.all(gripper_corners(grasp)[:, 2] >= 0.0)


def test_contacts_no_camera_sees_need_no_support() -> None:
    # One camera, on the box's +x side: the -x face of the box stays unseen.
    box = Box((0.025, 0.02, 0.04), center=np.array([0.0, 0.0, 0.04]))
    camera = np.array([[0.5, 0.05, 0.4]])
    rng = np.random.default_rng(7)
    cloud = union_cloud((box,), 0.0025, rng)
    points = cloud.points[visible_mask(cloud.points, cloud.normals, camera[0])]
    points = points + rng.normal(scale=0.001, size=points.shape)
    sq = Superquadric(0.1, 0.1, box.half_extents, box.rotation, box.center)
    blind = plan_from_hidden(points, [hidden(sq, points)], support_plane=TABLE)
    aware = plan_from_hidden(
        points, [hidden(sq, points)], support_plane=TABLE, camera_positions=camera
    )
    along_x = [g for g in aware.grasps if abs(g.closing_axis[0]) > 0.97]
    assert along_x, "the line through the unseen -x face survives with the camera known"
    assert not [g for g in blind.grasps if abs(g.closing_axis[0]) > 0.97]
    # Through the planner interface, the context's cameras are used the same way.
    context = PlanningContext(support_plane=TABLE, seed=0, camera_positions=camera)
    planned = HSQPlanner().plan(points, context)
    assert any(abs(g.closing_axis[0]) > 0.97 for g in planned.grasps)
    with pytest.raises(ValueError, match=r"camera_positions must be a \(C, 3\)"):
        plan_grasps(points, camera_positions=[1.0, 2.0])


def test_redraw_seeds_are_reproducible_and_distinct() -> None:
    assert redraw_seed(7, 0) == 7 and redraw_seed(None, 0) is None
    seeds = [redraw_seed(7, k) for k in (1, 2, 3)]
    assert seeds == [redraw_seed(7, k) for k in (1, 2, 3)]
    assert len({7, *seeds, redraw_seed(8, 1), redraw_seed(None, 1)}) == 6


@pytest.mark.parametrize(
    ("redraws", "grasps_on_draw", "draws"), [(2, 0, 1), (2, 1, 2), (2, 9, 3), (0, 1, 1)]
)
def test_no_grasp_redraws_stage_one_until_a_grasp_survives(
    monkeypatch, redraws: int, grasps_on_draw: int, draws: int
) -> None:
    import hsqbench.planner.hsq.planner as hsq_planner

    planner = HSQPlanner()
    planner.config = dataclasses.replace(
        planner.config,
        recovery=dataclasses.replace(planner.config.recovery, no_grasp_redraws=redraws),
    )
    seeds: list[int | None] = []

    def recover(cloud, groups, clean, seed):
        seeds.append(seed)
        return []

    def stage_two(cloud, hidden, config, gripper, context):
        found = len(seeds) - 1 == grasps_on_draw
        assert context.seed == seeds[-1]  # stage two plans with the draw's seed too
        grasps = [Grasp(np.zeros(3), np.eye(3), 0.04, 1.0)] if found else []
        return PlanResult(grasps=grasps, reason="" if found else "none")

    monkeypatch.setattr(planner, "_recover", recover)
    monkeypatch.setattr(hsq_planner, "plan_in_context", stage_two)
    cloud = np.random.default_rng(0).normal(scale=0.01, size=(3000, 3))
    result = planner.plan(cloud, PlanningContext(seed=5))
    assert seeds == [redraw_seed(5, k) for k in range(draws)]
    assert bool(result.grasps) == (grasps_on_draw < draws)
    assert result.reason == (
        ""
        if result.grasps
        else "none" + f" (on each of {draws} draws of stage one's K-means parts)" * (draws > 1)
    )


@pytest.mark.parametrize("bad", [-1, 1.5, True, "2"])
def test_no_grasp_redraws_must_be_a_whole_number(bad) -> None:
    with pytest.raises(ConfigError, match="no_grasp_redraws"):
        from_dict(PlannerConfig, {"recovery": {"no_grasp_redraws": bad}})
