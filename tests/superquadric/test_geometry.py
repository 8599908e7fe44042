"""Tests of hsqbench.superquadric: implicit function, sampling, normals, curvature, fit measures, mesh."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from hsqbench.superquadric import (
    CURVATURE_AXIS_OFFSET,
    EPS_MAX,
    EPS_MIN,
    Superquadric,
    alpha_beta,
    coverage_beta,
    gaussian_curvature_local,
    point_to_surface_alpha,
)

# (eps1, eps2, scale in metres): sphere, near-cube, cylinder, octahedron, pinched, extremes.
SHAPES = {
    "sphere": (1.0, 1.0, (0.04, 0.04, 0.04)),
    "ellipsoid": (1.0, 1.0, (0.015, 0.05, 0.03)),
    "cube": (0.1, 0.1, (0.03, 0.04, 0.05)),
    "cylinder": (0.1, 1.0, (0.03, 0.03, 0.05)),
    "octahedron": (2.0, 2.0, (0.04, 0.04, 0.04)),
    "octahedron_aniso": (2.0, 2.0, (0.02, 0.04, 0.05)),
    "pinched": (1.5, 1.5, (0.04, 0.03, 0.05)),
    "star_prism": (0.2, 1.8, (0.03, 0.04, 0.05)),
    "pinched_box": (1.8, 0.2, (0.03, 0.04, 0.05)),
    "eps_min": (0.05, 0.05, (0.05, 0.03, 0.04)),
    "eps_min_max": (0.05, 2.0, (0.03, 0.03, 0.06)),
    "bipyramid": (2.0, 0.05, (0.076, 0.047, 0.06)),
}


def random_pose(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    return Rotation.random(random_state=rng).as_matrix(), rng.uniform(-0.5, 0.5, 3)


def make(name: str, rng: np.random.Generator | None = None) -> Superquadric:
    e1, e2, scale = SHAPES[name]
    if rng is None:
        return Superquadric(e1, e2, scale)
    rotation, translation = random_pose(rng)
    return Superquadric(e1, e2, scale, rotation, translation)


def nn_distances(points: np.ndarray) -> np.ndarray:
    return cKDTree(points).query(points, k=2)[0][:, 1]


def nn_same_side(points: np.ndarray, normals: np.ndarray, k: int = 8) -> np.ndarray:
    """Nearest-neighbour distance among samples whose normals differ by less than 120 degrees.

    Across a sharp thin wedge the two sides come arbitrarily close in 3-D although they are far
    apart on the surface; the sampler keeps both sides, so evenness is judged side by side.
    """
    dist, idx = cKDTree(points).query(points, k=k)
    same = np.einsum("ij,ikj->ik", normals, normals[idx]) > -0.5
    same[:, 0] = False
    return dist[np.arange(points.shape[0]), np.argmax(same, axis=1)]


# ------------------------------------------------------------------------------------ sampling
@pytest.mark.parametrize("name", sorted(SHAPES))
def test_samples_lie_on_surface(name: str) -> None:
    sq = make(name, np.random.default_rng(1))
    points, _ = sq.sample_surface(0.003)
    assert points.shape[0] > 100
    np.testing.assert_allclose(sq.inside_outside(points), 1.0, rtol=1e-6)


@pytest.mark.parametrize("eps1", [0.1, 0.4, 1.0, 1.5, 2.0])
@pytest.mark.parametrize("eps2", [0.1, 0.6, 1.0, 2.0])
def test_samples_on_surface_across_exponents(eps1: float, eps2: float) -> None:
    rng = np.random.default_rng(int(100 * eps1 + 10 * eps2))
    rotation, translation = random_pose(rng)
    sq = Superquadric(eps1, eps2, rng.uniform(0.01, 0.06, 3), rotation, translation)
    points, normals = sq.sample_surface(0.004)
    np.testing.assert_allclose(sq.inside_outside(points), 1.0, rtol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("name", sorted(SHAPES))
@pytest.mark.parametrize("spacing", [0.002, 0.005])
def test_sampling_is_even(name: str, spacing: float) -> None:
    sq = make(name, np.random.default_rng(2))
    points, _ = sq.sample_surface(spacing)
    d = nn_distances(points)
    assert d.std() / d.mean() < 0.3
    assert 0.7 * spacing < d.mean() < 1.3 * spacing


@pytest.mark.parametrize("name", ["sphere", "cube", "cylinder", "octahedron", "pinched"])
def test_sampling_leaves_no_holes(name: str) -> None:
    """Random surface points (from a much finer sampling) are near some sample: no gaps."""
    sq = make(name)
    spacing = 0.004
    coarse, _ = sq.sample_surface(spacing)
    fine, _ = sq.sample_surface(spacing / 8)
    gap = cKDTree(coarse).query(fine)[0]
    assert gap.max() < 1.0 * spacing
    assert gap.mean() < 0.5 * spacing


def test_sampling_even_on_random_shapes() -> None:
    rng = np.random.default_rng(7)
    for _ in range(15):
        e1, e2 = rng.choice([0.05, 2.0, *rng.uniform(0.05, 2.0, 4)], size=2)
        sq = Superquadric(e1, e2, rng.uniform(0.01, 0.05, 3), *random_pose(rng))
        spacing = rng.uniform(0.003, 0.005)
        points, normals = sq.sample_surface(spacing)
        d = nn_same_side(points, normals)
        assert d.std() / d.mean() < 0.3, (e1, e2, sq.scale)
        assert 0.7 * spacing < d.mean() < 1.3 * spacing, (e1, e2, sq.scale)
        fine, _ = sq.sample_surface(spacing / 4)
        assert cKDTree(points).query(fine)[0].max() < 1.1 * spacing, (e1, e2, sq.scale)


@pytest.mark.parametrize("thickness", [2e-4, 1e-3])
def test_thin_plate_keeps_both_sides(thickness: float) -> None:
    sq = Superquadric(0.3, 1.0, (0.04, 0.04, 0.5 * thickness))
    spacing = 0.003
    points, normals = sq.sample_surface(spacing)
    top, bottom = np.count_nonzero(normals[:, 2] > 0.9), np.count_nonzero(normals[:, 2] < -0.9)
    assert top == bottom > 0.9 * np.pi * 0.04**2 / spacing**2
    d = nn_same_side(points, normals)
    assert d.std() / d.mean() < 0.3


def test_sample_count_scales_with_area() -> None:
    sq = make("sphere")
    n = sq.sample_surface(0.002)[0].shape[0]
    area = 4.0 * np.pi * 0.04**2
    # one sample per spacing^2 (square grid) up to the seams and the sphere's distortion
    assert 0.8 < n * 0.002**2 / area < 1.3


@pytest.mark.parametrize("spacing", [0.0, -0.001, np.nan, np.inf])
def test_sampling_rejects_bad_spacing(spacing: float) -> None:
    with pytest.raises(ValueError, match="spacing"):
        make("sphere").sample_surface(spacing)


def test_sampling_rejects_too_many_points() -> None:
    with pytest.raises(ValueError, match="MAX_SAMPLE_NODES"):
        make("sphere").sample_surface(1e-5)


# ------------------------------------------------------------------------------------ normals
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


# ------------------------------------------------------------------------------------ alpha / beta
def test_alpha_zero_for_points_on_surface() -> None:
    sq = make("cube", np.random.default_rng(4))
    spacing = 0.002
    cloud, _ = sq.sample_surface(0.0007)
    alpha = point_to_surface_alpha(cloud, sq, spacing)
    # discretisation bias only: about 0.4 spacing on average for a square grid
    assert alpha < 0.5 * spacing
    # and the samples themselves give exactly zero
    samples, _ = sq.sample_surface(spacing)
    assert point_to_surface_alpha(samples, sq, spacing) == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("name", ["sphere", "cube", "ellipsoid"])
def test_alpha_measures_normal_offset(name: str) -> None:
    sq = make(name, np.random.default_rng(5))
    cloud, normals = sq.sample_surface(0.002)
    alpha = point_to_surface_alpha(cloud + 0.003 * normals, sq, 0.001)
    assert alpha == pytest.approx(0.003, abs=0.0003)


def test_beta_full_and_half_cloud() -> None:
    sq = make("ellipsoid", np.random.default_rng(6))
    cloud, _ = sq.sample_surface(0.0015)
    spacing, d_th = 0.002, 0.002
    assert coverage_beta(cloud, sq, spacing, d_th) > 0.99
    side = (cloud - sq.translation) @ sq.rotation[:, 1] > 0.0
    half = coverage_beta(cloud[side], sq, spacing, d_th)
    assert 0.45 < half < 0.56
    alpha, beta = alpha_beta(cloud[side], sq, spacing, d_th)
    assert beta == half
    assert alpha == point_to_surface_alpha(cloud[side], sq, spacing)


def test_beta_far_cloud_is_zero() -> None:
    sq = make("sphere")
    assert coverage_beta(np.full((10, 3), 1.0), sq, 0.003, 0.005) == 0.0


@pytest.mark.parametrize("func", ["alpha", "beta", "both"])
def test_fit_measures_reject_empty_cloud(func: str) -> None:
    sq = make("sphere")
    empty = np.zeros((0, 3))
    with pytest.raises(ValueError, match="empty"):
        if func == "alpha":
            point_to_surface_alpha(empty, sq, 0.003)
        elif func == "beta":
            coverage_beta(empty, sq, 0.003, 0.005)
        else:
            alpha_beta(empty, sq, 0.003, 0.005)


def test_fit_measures_reject_bad_inputs() -> None:
    sq = make("sphere")
    with pytest.raises(ValueError, match="NaN"):
        point_to_surface_alpha(np.full((3, 3), np.nan), sq, 0.003)
    with pytest.raises(ValueError, match="d_th"):
        coverage_beta(np.zeros((3, 3)), sq, 0.003, 0.0)
    with pytest.raises(ValueError, match="shape"):
        point_to_surface_alpha(np.zeros((3, 2)), sq, 0.003)


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


# ------------------------------------------------------------------------------------ curvature
def test_curvature_of_sphere() -> None:
    radius = 0.035
    sq = Superquadric(1.0, 1.0, (radius,) * 3, *random_pose(np.random.default_rng(9)))
    points, _ = sq.sample_surface(0.003)
    # axis endpoints are included: the offset from the axis planes does not bias a smooth surface
    points = np.vstack([points, sq.to_world(np.diag(sq.scale)), sq.to_world(-np.diag(sq.scale))])
    np.testing.assert_allclose(sq.gaussian_curvature(points), 1.0 / radius**2, rtol=1e-9)
    # points off the surface are projected radially first
    off = sq.translation + 2.0 * (points - sq.translation)
    np.testing.assert_allclose(sq.gaussian_curvature(off), 1.0 / radius**2, rtol=1e-9)


def test_curvature_of_ellipsoid_matches_closed_form() -> None:
    a, b, c = 0.015, 0.05, 0.03
    sq = Superquadric(1.0, 1.0, (a, b, c), *random_pose(np.random.default_rng(10)))
    points, _ = sq.sample_surface(0.003)
    local = sq.to_local(points)
    expected = 1.0 / ((a * b * c) ** 2 * np.sum(local**2 / np.array([a, b, c]) ** 4, axis=1) ** 2)
    k = sq.gaussian_curvature(points)
    assert np.all(k > 0.0)
    np.testing.assert_allclose(k, expected, rtol=1e-6)


def _fd_curvature(sq: Superquadric, local: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """K = g^T adj(H) g / |g|^4 of rho = sqrt(G) by central differences (reference)."""

    def rho(x: np.ndarray) -> np.ndarray:
        return np.sqrt(sq.inside_outside_pow(x, local=True))

    e = np.eye(3) * h
    g = np.stack([(rho(local + e[i]) - rho(local - e[i])) / (2 * h) for i in range(3)], axis=1)
    hess = np.empty((local.shape[0], 3, 3))
    for i in range(3):
        for j in range(3):
            hess[:, i, j] = (
                rho(local + e[i] + e[j])
                - rho(local + e[i] - e[j])
                - rho(local - e[i] + e[j])
                + rho(local - e[i] - e[j])
            ) / (4 * h * h)
    adj = np.stack(
        [
            np.cross(hess[:, 1], hess[:, 2]),
            np.cross(hess[:, 2], hess[:, 0]),
            np.cross(hess[:, 0], hess[:, 1]),
        ],
        axis=2,
    )
    return np.einsum("ni,nij,nj->n", g, adj, g) / np.sum(g * g, axis=1) ** 2


@pytest.mark.parametrize("eps", [(0.5, 0.7), (1.5, 0.3), (0.3, 1.6), (1.2, 1.8), (0.2, 0.2)])
def test_curvature_matches_finite_differences(eps: tuple[float, float]) -> None:
    sq = Superquadric(*eps, (0.03, 0.04, 0.05))
    local, _ = sq.sample_surface(0.004)
    local = local[np.all(np.abs(local) > 0.003, axis=1)]  # away from the non-smooth axis planes
    local = local[np.random.default_rng(11).choice(local.shape[0], 40, replace=False)]
    k = sq.gaussian_curvature(local)
    np.testing.assert_allclose(k, _fd_curvature(sq, local), rtol=1e-4, atol=1e-2)


def test_curvature_zero_on_cube_faces_and_cylinder_side() -> None:
    cube = Superquadric(0.1, 0.1, (0.03, 0.04, 0.05))
    face = np.array(
        [[0.0, 0.0, 0.05], [0.01, -0.02, 0.05], [0.03, 0.01, -0.02], [-0.015, 0.04, 0.03]]
    )
    face /= np.sqrt(cube.inside_outside_pow(face))[:, None]
    # zero up to (fraction of the face)^(2/eps - 2): at least 1e6 below a 3 cm sphere's 1/R^2
    assert np.all(cube.gaussian_curvature(face) * 0.03**2 < 1e-6)
    # near the rounded edges it is large
    assert cube.gaussian_curvature([[0.03, 0.04, 0.05]])[0] > 1e4
    cylinder = Superquadric(0.1, 1.0, (0.03, 0.03, 0.05))
    angles = np.linspace(0.0, 2.0 * np.pi, 13)
    side = np.column_stack(
        [0.03 * np.cos(angles), 0.03 * np.sin(angles), np.linspace(-0.03, 0.03, 13)]
    )
    # eps1 = 0.1 is not exactly straight: up to 60 % of the height K is 1e3 times below 1/R^2
    assert np.all(cylinder.gaussian_curvature(side) * 0.03**2 < 1e-3)
    # the flat caps too; the rim is curved
    caps = cylinder.gaussian_curvature([[0.01, 0.0, 0.05], [0.0, -0.02, -0.05]])
    assert np.all(caps * 0.03**2 < 1e-3)
    assert cylinder.gaussian_curvature([[0.0, 0.03, 0.05]])[0] * 0.03**2 > 1.0


@pytest.mark.parametrize("eps1", [EPS_MIN, 0.5, 1.0, 1.5, 1.9, EPS_MAX])
@pytest.mark.parametrize("eps2", [EPS_MIN, 0.5, 1.0, 1.5, 1.9, EPS_MAX])
def test_curvature_finite_and_non_negative_on_sampled_surfaces(eps1: float, eps2: float) -> None:
    sq = Superquadric(eps1, eps2, (0.02, 0.03, 0.05), *random_pose(np.random.default_rng(12)))
    points, _ = sq.sample_surface(0.004)
    tips = sq.to_world(np.vstack([np.diag(sq.scale), -np.diag(sq.scale)]))
    k = sq.gaussian_curvature(np.vstack([points, tips]))
    assert np.all(np.isfinite(k))
    assert np.all(k >= 0.0)


def test_curvature_at_pinched_tip_is_large_but_finite() -> None:
    """eps > 1: unbounded at the axis endpoint, so the tip is evaluated at the documented offset."""
    sq = Superquadric(1.5, 1.5, (0.03, 0.03, 0.03))
    tip = sq.gaussian_curvature([[0.0, 0.0, 0.03]])[0]
    near = sq.gaussian_curvature([[0.003, 0.003, 0.03]])[0]
    offset = np.full(3, CURVATURE_AXIS_OFFSET * 0.03)
    offset[2] = 0.03
    assert np.isfinite(tip) and tip > 100 * near > 0
    assert tip == pytest.approx(sq.gaussian_curvature(offset[None])[0], rel=1e-3)


def test_curvature_rows_with_own_parameters() -> None:
    shapes = [
        Superquadric(0.3, 1.2, (0.02, 0.03, 0.04)),
        Superquadric(1.0, 1.0, (0.05, 0.05, 0.05)),
    ]
    local = np.array([[0.01, 0.01, 0.03], [0.0, 0.03, 0.04]])
    rows = gaussian_curvature_local(
        local,
        [s.eps1 for s in shapes],
        [s.eps2 for s in shapes],
        np.array([s.scale for s in shapes]),
    )
    single = [s.gaussian_curvature(p[None])[0] for s, p in zip(shapes, local, strict=True)]
    np.testing.assert_allclose(rows, single, rtol=1e-12)
    assert rows[1] == pytest.approx(1.0 / 0.05**2)
    with pytest.raises(ValueError, match="eps1, eps2"):
        gaussian_curvature_local(local, 2.5, 1.0, (0.01, 0.01, 0.01))
    with pytest.raises(ValueError, match="finite"):
        gaussian_curvature_local(local, 1.0, 1.0, (0.0, 0.01, 0.01))


# ------------------------------------------------------------------------------------ mesh, volume
@pytest.mark.parametrize("name", sorted(SHAPES))
def test_mesh_is_watertight_on_surface_with_right_volume(name: str) -> None:
    sq = make(name, np.random.default_rng(13))
    mesh = sq.to_trimesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    np.testing.assert_allclose(sq.inside_outside(mesh.vertices), 1.0, rtol=1e-9)
    assert mesh.volume == pytest.approx(sq.volume, rel=0.005)  # positive: faces point outward
    vertices, faces = sq.to_mesh(8)
    assert faces.dtype.kind == "i" and faces.max() == vertices.shape[0] - 1


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


def test_mesh_rejects_coarse_resolution() -> None:
    with pytest.raises(ValueError, match="n_quarter"):
        make("sphere").to_mesh(1)


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
