"""The synthetic shapes shared by the planner tests."""

from __future__ import annotations

import numpy as np

from tests.shapes import (
    Box,
    Cylinder,
    l_of_two_boxes,
    mug_with_handle,
    random_rotation,
    random_superquadric,
    superquadric_cloud,
    surface_distance,
    union_cloud,
    view_surface_distance,
    visible_mask,
)


def test_primitives_sample_their_surface() -> None:
    rng = np.random.default_rng(0)
    for prim in (
        Box((0.03, 0.02, 0.01), random_rotation(rng), np.array([0.1, 0.0, 0.0])),
        Cylinder(0.02, 0.05, random_rotation(rng), np.array([0.0, 0.1, 0.0])),
    ):
        pts, normals = prim.sample_surface(2000, rng)
        assert np.abs(prim.distance(pts)).max() < 1e-12 and prim.contains(pts).all()
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0)
        out = pts + 0.003 * normals
        np.testing.assert_allclose(prim.distance(out), 0.003, atol=1e-9)
        assert not prim.contains(out).any()


def test_union_keeps_only_the_outer_surface() -> None:
    rng = np.random.default_rng(1)
    parts = mug_with_handle(random_rotation(rng))
    pc = union_cloud(parts, 0.002, rng)
    assert set(np.unique(pc.labels)) == {0, 1}
    for i in range(len(parts)):
        others = [p for j, p in enumerate(parts) if j != i]
        on_i = pc.points[pc.labels == i]
        assert not any(o.contains(on_i).any() for o in others)


def test_one_camera_sees_the_facing_side_only() -> None:
    rng = np.random.default_rng(2)
    box = Box((0.05, 0.05, 0.05))
    pts, normals = box.sample_surface(20000, rng)
    seen = visible_mask(pts, normals, np.array([0.0, 0.0, 1.0]))
    assert np.all(normals[seen, 2] > 0.5) and seen[normals[:, 2] > 0.5].mean() > 0.95
    # An L seen from above: the base's top under the upright is hidden by the upright.
    pc = union_cloud(l_of_two_boxes(), 0.002, rng)
    seen = visible_mask(pc.points, pc.normals, np.array([-0.04, 0.0, 1.0]))
    base_top = (pc.labels == 0) & (pc.normals[:, 2] > 0.5)
    assert seen[base_top].mean() > 0.9 and seen[pc.labels == 1].any()


def test_superquadric_clouds_and_distances() -> None:
    rng = np.random.default_rng(3)
    sq = random_superquadric(rng)
    assert 0.1 <= sq.eps1 <= 1.9 and np.all((sq.scale >= 0.015) & (sq.scale <= 0.1))
    cloud = superquadric_cloud(sq, rng, one_sided=True)
    assert cloud.camera is not None and 0.15 < cloud.outliers.mean() < 0.25
    assert surface_distance(sq, sq) < 0.001
    assert view_surface_distance(sq, sq, cloud.camera) < 0.001
    bigger = type(sq)(sq.eps1, sq.eps2, sq.scale + 0.005, sq.rotation, sq.translation)
    assert 0.003 < surface_distance(sq, bigger) < 0.006
