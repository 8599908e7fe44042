"""Synthetic point clouds for planner tests: primitives, unions of primitives, camera views.

Everything is in metres and seeded through ``np.random.Generator``. The primitives here are exact
(boxes and cylinders with sharp edges), so that a test measures a recovered superquadric against
the true geometry, not against another superquadric.

Shared by the stage-one (recovery) and stage-two (grasp) tests::

    from tests.shapes import l_of_two_boxes, union_cloud, visible_mask, add_noise_and_outliers

Random superquadrics, their noisy clouds (full or one-sided) and surface distances for
accuracy tests: :func:`random_superquadric`, :func:`superquadric_cloud`,
:func:`surface_distance`, :func:`view_surface_distance`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from hsqbench.superquadric.geometry import Superquadric

Array = NDArray[np.float64]


def random_rotation(rng: np.random.Generator) -> Array:
    """A rotation matrix drawn uniformly from SO(3)."""
    return Rotation.random(random_state=rng).as_matrix()


# --------------------------------------------------------------------------------- primitives
@dataclass(frozen=True)
class Box:
    """A solid box: half extents (m), rotation (columns = box axes in the world), centre (m)."""

    half_extents: tuple[float, float, float]
    rotation: Array = field(default_factory=lambda: np.eye(3))
    center: Array = field(default_factory=lambda: np.zeros(3))

    def _local(self, points: Array) -> Array:
        return (np.asarray(points, dtype=float) - self.center) @ self.rotation

    def area(self) -> float:
        a, b, c = self.half_extents
        return 8.0 * (a * b + b * c + a * c)

    def sample_surface(self, n: int, rng: np.random.Generator) -> tuple[Array, Array]:
        """``n`` points uniform over the surface (area-weighted faces) and their outward normals."""
        h = np.asarray(self.half_extents, dtype=float)
        face_area = np.array([h[1] * h[2], h[0] * h[2], h[0] * h[1]] * 2)
        face = rng.choice(6, size=n, p=face_area / face_area.sum())
        axis = face % 3
        sign = np.where(face < 3, 1.0, -1.0)
        local = rng.uniform(-1.0, 1.0, size=(n, 3)) * h
        local[np.arange(n), axis] = sign * h[axis]
        normals = np.zeros((n, 3))
        normals[np.arange(n), axis] = sign
        return local @ self.rotation.T + self.center, normals @ self.rotation.T

    def contains(self, points: Array, tol: float = 1e-6) -> NDArray[np.bool_]:
        """Inside or within ``tol`` of the surface."""
        q = np.abs(self._local(points))
        return np.all(q <= np.asarray(self.half_extents) + tol, axis=1)

    def distance(self, points: Array) -> Array:
        """Unsigned Euclidean distance to the box surface (m)."""
        d = np.abs(self._local(points)) - np.asarray(self.half_extents)
        outside = np.linalg.norm(np.maximum(d, 0.0), axis=1)
        inside = -np.minimum(d.max(axis=1), 0.0)
        return outside + inside


@dataclass(frozen=True)
class Cylinder:
    """A solid cylinder along its local z axis: radius and half height (m), rotation, centre (m)."""

    radius: float
    half_height: float
    rotation: Array = field(default_factory=lambda: np.eye(3))
    center: Array = field(default_factory=lambda: np.zeros(3))

    def _local(self, points: Array) -> Array:
        return (np.asarray(points, dtype=float) - self.center) @ self.rotation

    def area(self) -> float:
        return 2.0 * np.pi * self.radius * (2.0 * self.half_height + self.radius)

    def sample_surface(self, n: int, rng: np.random.Generator) -> tuple[Array, Array]:
        """``n`` points uniform over side and caps, and their outward normals."""
        r, h = self.radius, self.half_height
        side = 4.0 * np.pi * r * h
        cap = np.pi * r * r
        part = rng.choice(3, size=n, p=np.array([side, cap, cap]) / (side + 2 * cap))
        theta = rng.uniform(0.0, 2.0 * np.pi, size=n)
        rho = np.where(part == 0, r, r * np.sqrt(rng.uniform(0.0, 1.0, size=n)))
        z = np.select([part == 0, part == 1], [rng.uniform(-h, h, size=n), h], -h)
        local = np.column_stack([rho * np.cos(theta), rho * np.sin(theta), z])
        normals = np.zeros((n, 3))
        normals[part == 0, :2] = np.column_stack([np.cos(theta), np.sin(theta)])[part == 0]
        normals[part == 1, 2] = 1.0
        normals[part == 2, 2] = -1.0
        return local @ self.rotation.T + self.center, normals @ self.rotation.T

    def contains(self, points: Array, tol: float = 1e-6) -> NDArray[np.bool_]:
        """Inside or within ``tol`` of the surface."""
        q = self._local(points)
        return (np.hypot(q[:, 0], q[:, 1]) <= self.radius + tol) & (
            np.abs(q[:, 2]) <= self.half_height + tol
        )

    def distance(self, points: Array) -> Array:
        """Unsigned Euclidean distance to the cylinder surface (m)."""
        q = self._local(points)
        d = np.column_stack(
            [np.hypot(q[:, 0], q[:, 1]) - self.radius, np.abs(q[:, 2]) - self.half_height]
        )
        outside = np.linalg.norm(np.maximum(d, 0.0), axis=1)
        inside = -np.minimum(d.max(axis=1), 0.0)
        return outside + inside


Primitive = Box | Cylinder


# --------------------------------------------------------------------------------- unions
@dataclass(frozen=True)
class PartCloud:
    """Points on the outer surface of a union of primitives.

    Attributes:
        points: (N, 3) surface points, metres (noise-free unless a caller added noise).
        normals: (N, 3) outward unit normals.
        labels: (N,) index into ``parts`` of the primitive each point lies on.
        parts: the primitives.
    """

    points: Array
    normals: Array
    labels: NDArray[np.int64]
    parts: tuple[Primitive, ...]


def union_cloud(
    parts: tuple[Primitive, ...], spacing: float, rng: np.random.Generator
) -> PartCloud:
    """Sample each primitive with about one point per ``spacing``² of area, keep the outer surface.

    A point of one part that lies inside (or on) another part is hidden in the union and dropped.
    """
    pts, nrm, lab = [], [], []
    for i, part in enumerate(parts):
        p, n = part.sample_surface(round(part.area() / spacing**2), rng)
        keep = np.ones(len(p), dtype=bool)
        for j, other in enumerate(parts):
            if j != i:
                keep &= ~other.contains(p)
        pts.append(p[keep])
        nrm.append(n[keep])
        lab.append(np.full(int(keep.sum()), i))
    return PartCloud(np.concatenate(pts), np.concatenate(nrm), np.concatenate(lab), tuple(parts))


def _placed(rotation: Array, translation: Array, parts: list[Primitive]) -> tuple[Primitive, ...]:
    """Apply one rigid transform to a list of primitives."""
    out: list[Primitive] = []
    for p in parts:
        rot = rotation @ p.rotation
        centre = rotation @ p.center + translation
        if isinstance(p, Box):
            out.append(Box(p.half_extents, rot, centre))
        else:
            out.append(Cylinder(p.radius, p.half_height, rot, centre))
    return tuple(out)


def l_of_two_boxes(
    rotation: Array | None = None, translation: Array | None = None
) -> tuple[Primitive, ...]:
    """An L: a 12 x 4 x 3 cm base and a 4 x 4 x 9 cm upright standing on one end of it."""
    base = Box((0.06, 0.02, 0.015), center=np.array([0.0, 0.0, 0.015]))
    upright = Box((0.02, 0.02, 0.045), center=np.array([-0.04, 0.0, 0.03 + 0.045]))
    return _placed(_rot(rotation), _trans(translation), [base, upright])


def cylinder_with_box_on_top(
    rotation: Array | None = None, translation: Array | None = None
) -> tuple[Primitive, ...]:
    """A 7 cm wide, 12 cm tall cylinder carrying a 5 x 5 x 4 cm box on its top."""
    body = Cylinder(0.035, 0.06, center=np.array([0.0, 0.0, 0.06]))
    top = Box((0.025, 0.025, 0.02), center=np.array([0.0, 0.0, 0.12 + 0.02]))
    return _placed(_rot(rotation), _trans(translation), [body, top])


def mug_with_handle(
    rotation: Array | None = None, translation: Array | None = None
) -> tuple[Primitive, ...]:
    """A mug-like 8 cm wide, 10 cm tall cylinder with a solid 3 x 1.6 x 7 cm handle on its side.

    The handle is a solid bar: a superquadric cannot describe the hole of a looped handle, and a
    bar keeps the test about finding parts, not about a shape no primitive can fit.
    """
    body = Cylinder(0.04, 0.05, center=np.array([0.0, 0.0, 0.05]))
    # The bar reaches 5 mm into the wall so that the union is one connected solid.
    handle = Box((0.0175, 0.008, 0.035), center=np.array([0.04 + 0.0175 - 0.005, 0.0, 0.05]))
    return _placed(_rot(rotation), _trans(translation), [body, handle])


def _rot(rotation: Array | None) -> Array:
    return np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)


def _trans(translation: Array | None) -> Array:
    return np.zeros(3) if translation is None else np.asarray(translation, dtype=float)


# --------------------------------------------------------------------------------- sensing
def visible_mask(
    points: Array,
    normals: Array,
    camera: Array,
    pixel_m: float = 0.001,
    depth_tol_m: float = 0.003,
) -> NDArray[np.bool_]:
    """Which surface points a pinhole camera at ``camera`` (m) sees.

    A point is visible when its normal faces the camera and, in a z-buffer whose pixels are
    ``pixel_m`` wide at the cloud's distance, it lies within ``depth_tol_m`` of the nearest point
    of its pixel (so a point behind another part of the object is occluded).
    """
    points = np.asarray(points, dtype=float)
    camera = np.asarray(camera, dtype=float)
    to_cam = camera - points
    facing = np.einsum("ij,ij->i", normals, to_cam) > 0.0
    axis = points.mean(axis=0) - camera
    dist = np.linalg.norm(axis)
    axis /= dist
    # An orthonormal image frame (u, v, axis).
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    rel = points - camera
    depth = rel @ axis
    pix = np.floor(np.column_stack([rel @ u, rel @ v]) / depth[:, None] * dist / pixel_m)
    pix = pix.astype(np.int64)
    _, key = np.unique(pix, axis=0, return_inverse=True)
    key = key.ravel()
    nearest = np.full(key.max() + 1, np.inf)
    cand = np.where(facing, depth, np.inf)
    np.minimum.at(nearest, key, cand)
    return facing & (depth <= nearest[key] + depth_tol_m)


def random_view_direction(rng: np.random.Generator) -> Array:
    """A unit vector uniform on the sphere."""
    d = rng.normal(size=3)
    return d / np.linalg.norm(d)


def add_noise_and_outliers(
    points: Array,
    noise_m: float,
    outlier_fraction: float,
    rng: np.random.Generator,
) -> tuple[Array, NDArray[np.bool_]]:
    """Isotropic Gaussian noise (std ``noise_m`` per axis) plus uniform outliers in the bounding box.

    ``outlier_fraction`` is the share of outliers in the returned cloud. Returns the cloud (inliers
    first, then outliers) and a mask of the outliers.
    """
    noisy = points + rng.normal(scale=noise_m, size=points.shape)
    n_out = round(len(points) * outlier_fraction / (1.0 - outlier_fraction))
    lo, hi = noisy.min(axis=0), noisy.max(axis=0)
    outliers = rng.uniform(lo, hi, size=(n_out, 3))
    mask = np.concatenate([np.zeros(len(noisy), bool), np.ones(n_out, bool)])
    return np.concatenate([noisy, outliers]), mask


# --------------------------------------------------------------------------------- superquadrics
def random_superquadric(
    rng: np.random.Generator,
    eps_range: tuple[float, float] = (0.1, 1.9),
    scale_range_m: tuple[float, float] = (0.015, 0.10),
    translation_range_m: float = 0.1,
) -> Superquadric:
    """A superquadric with uniform eps1, eps2 and semi-axes, a uniform rotation and a centre in
    a cube of half side ``translation_range_m``."""
    eps = rng.uniform(*eps_range, size=2)
    scale = rng.uniform(*scale_range_m, size=3)
    centre = rng.uniform(-translation_range_m, translation_range_m, size=3)
    return Superquadric(eps[0], eps[1], scale, random_rotation(rng), centre)


def surface_distance(a: Superquadric, b: Superquadric, spacing: float = 0.0015) -> float:
    """Symmetric surface distance (m): the mean of the mean nearest-neighbour distances from an
    even sampling of each surface to one of the other, at ``spacing``.

    Identical surfaces score about ``0.4 * spacing`` (the samplings do not coincide): the
    measure errs on the strict side. It compares surfaces, not parameters, so a superquadric
    and an equivalent one with permuted axes score the same.
    """
    pa, _ = a.sample_surface(spacing)
    pb, _ = b.sample_surface(spacing)
    return 0.5 * float(cKDTree(pb).query(pa)[0].mean() + cKDTree(pa).query(pb)[0].mean())


def view_surface_distance(
    true: Superquadric, fitted: Superquadric, camera: Array, spacing: float = 0.0015
) -> float:
    """Symmetric distance (m) restricted to what one camera at ``camera`` can check.

    The mean of (1) the mean distance from the true surface's samples visible from the camera
    to the fitted surface, and (2) the mean distance from the fitted surface's samples visible
    from the camera to the true surface. The hidden back of either surface does not count:
    a single view does not constrain it. A fit that bulges toward the camera, or extends
    sideways beyond the object, still counts through (2).
    """
    pt, nt = true.sample_surface(spacing)
    pf, nf = fitted.sample_surface(spacing)
    vt = visible_mask(pt, nt, camera, pixel_m=spacing)
    vf = visible_mask(pf, nf, camera, pixel_m=spacing)
    return 0.5 * float(cKDTree(pf).query(pt[vt])[0].mean() + cKDTree(pt).query(pf[vf])[0].mean())


@dataclass(frozen=True)
class SQCloud:
    """A noisy superquadric cloud: points (m), the outlier mask, the camera (None: full view)."""

    points: Array
    outliers: NDArray[np.bool_]
    camera: Array | None


def superquadric_cloud(
    sq: Superquadric,
    rng: np.random.Generator,
    spacing: float = 0.002,
    noise_m: float = 0.001,
    outlier_fraction: float = 0.2,
    one_sided: bool = False,
    camera_distance_m: float = 0.5,
) -> SQCloud:
    """An even ``spacing`` sampling of ``sq`` (or of what a camera in a random direction sees),
    plus Gaussian noise and uniform outliers in the bounding box (:func:`add_noise_and_outliers`)."""
    points, normals = sq.sample_surface(spacing)
    camera = None
    if one_sided:
        camera = sq.translation + camera_distance_m * random_view_direction(rng)
        points = points[visible_mask(points, normals, camera, pixel_m=spacing)]
    cloud, outliers = add_noise_and_outliers(points, noise_m, outlier_fraction, rng)
    return SQCloud(cloud, outliers, camera)
