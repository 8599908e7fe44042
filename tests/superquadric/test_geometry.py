"""The Superquadric class (hsqbench.superquadric.geometry): implicit function, radial distance, normals, frames, volume."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from hsqbench.superquadric.geometry import Superquadric
from hsqbench.superquadric.primitives import EPS_MAX, EPS_MIN
from tests.superquadric.examples import SHAPES, make, random_pose


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_normals_unit_outward_and_match_finite_differences(name: str) -> None:
    rng = np.random.default_rng(3)
    sq = make(name, rng)
    points, normals = sq.sample_surface(0.004)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)
    # outward: G grows along the normal (valid for pinched shapes too)
    step = 1e-6
    assert np.all(sq.inside_outside_pow(points + step * normals) > 1.0)
    assert np.all(sq.inside_outside_pow(points - step * normals) < 1.0)
    # every superquadric with eps <= 2 is convex and contains its centre
    assert np.all(np.einsum("ij,ij->i", normals, points - sq.translation) > 0.0)
    # central differences of G; keep away from the axis planes where eps > 1 makes G non-smooth
    local = sq.to_local(points)
    smooth = np.all(np.abs(local) > 1e-3, axis=1)
    h = 1e-7
    fd = np.stack(
        [
            sq.inside_outside_pow(points[smooth] + h * e)
            - sq.inside_outside_pow(points[smooth] - h * e)
            for e in np.eye(3)
        ],
        axis=1,
    )
    fd /= np.linalg.norm(fd, axis=1, keepdims=True)
    assert smooth.sum() > 50
    np.testing.assert_allclose(np.einsum("ij,ij->i", fd, normals[smooth]), 1.0, atol=1e-5)
    # on an axis plane the normal of a shape with eps > 1 turns like |x|^(2/eps - 1), so rounding
    # off the plane moves it; elsewhere normals() agrees with the sampler to rounding
    np.testing.assert_allclose(sq.normals(points[smooth]), normals[smooth], atol=1e-9)


# ------------------------------------------------------------------------------------ implicit function
SPECIAL_POINTS = np.array(
    [
        [0.0, 0.0, 0.0],
        [1e6, 0.0, 0.0],
        [0.0, -1e6, 1e6],
        [0.0, 0.0, 0.05],
        [0.0, 0.03, 0.0],
        [1e-300, 0.0, 0.0],
        [0.0, 0.0, -1e-12],
        [0.02, 0.02, 0.02],
    ]
)


@pytest.mark.parametrize("eps1", [EPS_MIN, 0.3, 1.0, 1.7, EPS_MAX])
@pytest.mark.parametrize("eps2", [EPS_MIN, 0.6, 1.0, EPS_MAX])
def test_implicit_function_and_radial_distance_finite_everywhere(eps1: float, eps2: float) -> None:
    sq = Superquadric(eps1, eps2, (0.03, 0.04, 0.05))
    points = np.vstack([SPECIAL_POINTS, sq.sample_surface(0.005)[0]])
    for values in (
        sq.inside_outside(points),
        sq.inside_outside_pow(points),
        sq.radial_distance(points),
        sq.gaussian_curvature(points),
        sq.normals(points),
    ):
        assert np.all(np.isfinite(values))
    surface = points[len(SPECIAL_POINTS) :]
    np.testing.assert_allclose(sq.radial_distance(surface), 0.0, atol=1e-12)
    # along the axes the surface is at the semi-axis
    axes = np.vstack([np.diag(sq.scale) * 3.0, -np.diag(sq.scale) * 0.5])
    np.testing.assert_allclose(
        sq.radial_distance(axes), np.concatenate([2 * sq.scale, 0.5 * sq.scale])
    )


def test_radial_distance_of_sphere_is_distance_to_sphere() -> None:
    rng = np.random.default_rng(8)
    rotation, translation = random_pose(rng)
    sq = Superquadric(1.0, 1.0, (0.04, 0.04, 0.04), rotation, translation)
    points = translation + rng.normal(size=(500, 3)) * rng.uniform(0.0, 0.2, (500, 1))
    expected = np.abs(np.linalg.norm(points - translation, axis=1) - 0.04)
    np.testing.assert_allclose(sq.radial_distance(points), expected, atol=1e-12)


def test_closed_form_volumes() -> None:
    assert Superquadric(1.0, 1.0, (0.01, 0.02, 0.03)).volume == pytest.approx(4 / 3 * np.pi * 6e-6)
    assert Superquadric(2.0, 2.0, (0.01, 0.02, 0.03)).volume == pytest.approx(8 / 6 * 6e-6)
    # a cylinder with eps1 -> 0: pi r^2 h
    assert Superquadric(EPS_MIN, 1.0, (0.01, 0.01, 0.03)).volume == pytest.approx(
        np.pi * 1e-4 * 0.06, rel=0.05
    )


def test_principal_axes_and_repr() -> None:
    sq = make("cube", np.random.default_rng(14))
    np.testing.assert_allclose(
        sq.principal_axes[:, 2], sq.to_world([[0, 0, 1]])[0] - sq.translation
    )
    text = repr(sq)
    assert text.startswith("Superquadric(eps=(0.1, 0.1), scale_mm=[30.0, 40.0, 50.0]")
    assert "\n" not in text


# ------------------------------------------------------------------------------------ properties
eps_st = st.floats(EPS_MIN, EPS_MAX)
scale_st = st.tuples(*[st.floats(0.002, 0.2)] * 3)
quat_st = st.tuples(*[st.floats(-1.0, 1.0)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1)
trans_st = st.tuples(*[st.floats(-1.0, 1.0)] * 3)
points_st = st.lists(st.tuples(*[st.floats(-2.0, 2.0)] * 3), min_size=1, max_size=20)


def _sq(e1: float, e2: float, scale: tuple, quat: tuple, trans: tuple) -> Superquadric:
    return Superquadric(e1, e2, scale, Rotation.from_quat(quat).as_matrix(), trans)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(eps_st, eps_st, scale_st, quat_st, trans_st)
def test_vector_round_trip(e1: float, e2: float, scale: tuple, quat: tuple, trans: tuple) -> None:
    sq = _sq(e1, e2, scale, quat, trans)
    vector = sq.to_vector()
    back = Superquadric.from_vector(vector)
    np.testing.assert_allclose(back.rotation, sq.rotation, atol=1e-9)
    if np.linalg.norm(vector[5:8]) < np.pi - 1e-6:  # at pi, +/- rotvec are the same rotation
        np.testing.assert_allclose(back.to_vector(), vector, atol=1e-9)
    assert (back.eps1, back.eps2) == (sq.eps1, sq.eps2)
    np.testing.assert_array_equal(back.scale, sq.scale)
    np.testing.assert_array_equal(back.translation, sq.translation)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(eps_st, eps_st, scale_st, quat_st, trans_st, points_st)
def test_frame_round_trip(
    e1: float, e2: float, scale: tuple, quat: tuple, trans: tuple, points: list
) -> None:
    sq = _sq(e1, e2, scale, quat, trans)
    p = np.array(points)
    np.testing.assert_allclose(sq.to_world(sq.to_local(p)), p, atol=1e-12)
    np.testing.assert_allclose(sq.to_local(sq.to_world(p)), p, atol=1e-12)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(eps_st, eps_st, scale_st, quat_st, trans_st, quat_st, trans_st, points_st)
def test_inside_outside_invariant_under_pose_change(
    e1: float,
    e2: float,
    scale: tuple,
    quat: tuple,
    trans: tuple,
    move_quat: tuple,
    move_trans: tuple,
    points: list,
) -> None:
    sq = _sq(e1, e2, scale, quat, trans)
    move = Rotation.from_quat(move_quat).as_matrix()
    shift = np.array(move_trans)
    moved = Superquadric(e1, e2, scale, move @ sq.rotation, move @ sq.translation + shift)
    p = np.array(points)
    q = p @ move.T + shift
    # G is homogeneous of degree 2: rounding of the pose gives ~1e-32 at the centre itself
    np.testing.assert_allclose(
        moved.inside_outside_pow(q), sq.inside_outside_pow(p), rtol=1e-9, atol=1e-20
    )
    # the ray direction is undefined at the centre: compare away from it
    away = np.linalg.norm(p - sq.translation, axis=1) > 1e-9
    np.testing.assert_allclose(
        moved.radial_distance(q[away]), sq.radial_distance(p[away]), rtol=1e-7, atol=1e-12
    )


@settings(max_examples=60, deadline=None, derandomize=True)
@given(eps_st, eps_st, scale_st, quat_st, trans_st, points_st)
def test_radial_distance_non_negative_and_finite(
    e1: float, e2: float, scale: tuple, quat: tuple, trans: tuple, points: list
) -> None:
    sq = _sq(e1, e2, scale, quat, trans)
    p = np.vstack([np.array(points), sq.translation])
    d = sq.radial_distance(p)
    assert np.all(np.isfinite(d)) and np.all(d >= 0.0)
    # the surface lies within sqrt(3) max semi-axis of the centre (box corners)
    assert np.all(d <= np.linalg.norm(p - sq.translation, axis=1) + np.sqrt(3) * sq.scale.max())
    assert np.all(np.isfinite(sq.inside_outside(p)))
