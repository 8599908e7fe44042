"""Depth-sensor error models: time-of-flight depth noise and extrinsic calibration error.

**Time-of-flight noise** (:func:`apply_tof_noise`), applied to a clean planar-depth image
(metres, 0 = invalid), in this order:

1. *Depth discontinuities*: a pixel is on an edge when the valid depths of its 3 x 3
   neighbourhood span more than ``edge_jump_m``; ``z_near``/``z_far`` are their extremes.
2. *Flying pixels*: an edge pixel becomes, with probability ``flying_pixel_prob``, a mixed pixel
   ``z = z_near + w (z_far - z_near)``, ``w ~ U(0, 1)``: the pixel's footprint straddles the
   foreground and the background and an AMCW ToF camera reports a depth between them.
3. *Range noise*: the measured range ``r`` (distance from the optical centre along the ray) gets
   Gaussian noise ``sigma(r) = sigma_const_m + sigma_quad_per_m * r^2``; the pixel keeps its ray,
   so the planar depth scales by ``(r + sigma n) / r``.
4. *Dropout*: each pixel is invalidated (z = 0) with probability
   ``p = dropout_prob + (1 - dropout_prob) * ramp(theta)``, where ``theta`` is the angle between
   the ray and the surface normal (from the clean depth image) and ``ramp`` rises linearly from
   0 at ``grazing_start_deg`` to 1 at ``grazing_full_deg`` (the returned signal falls with
   ``cos theta`` and the camera invalidates weak pixels). On edges the normal is undefined:
   flying pixels are dropped with ``dropout_prob``, the other edge pixels with
   ``max(dropout_prob, edge_dropout_prob)`` (the sensor's own invalidation of mixed pixels).

Numbers (see ``configs/perception.yaml``): the Azure Kinect's specification gives a random-error
standard deviation <= 17 mm and a systematic error < 11 mm + 0.1 % of the distance over its range
(Microsoft, "Azure Kinect DK hardware specifications"; confirmed by Tölgyessy et al., "Evaluation
of the Azure Kinect and Its Comparison to Kinect V1 and Kinect V2", Sensors 21(2):413, 2021).
Those are upper bounds; the default curve (0.75 mm at 0.5 m, 1.5 mm at 1 m, 13 mm at 3.5 m) and
the dropout and flying-pixel rates are *assumptions* that stay inside them.

**Calibration error** (:func:`calibration_errors`): each camera's believed pose is its true pose
composed with a fixed rigid error, ``T_believed = T_true @ E``, where ``E`` rotates by
``rotation_deg`` about a uniformly random axis and translates by ``translation_m`` in a uniformly
random direction (both in the camera's optical frame). Drawn once per camera from the generator.

Every random number comes from the ``np.random.Generator`` passed in, with a fixed number of
draws per image, so results are reproducible from the seed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hsqbench.sim.camera import backproject

Array = NDArray[np.float64]


@dataclass(frozen=True)
class TofNoiseConfig:
    """Time-of-flight depth errors (see the module docstring). Lengths in metres."""

    sigma_const_m: float = 0.0005
    sigma_quad_per_m: float = 0.001
    dropout_prob: float = 0.01
    grazing_start_deg: float = 70.0
    grazing_full_deg: float = 85.0
    edge_jump_m: float = 0.02
    flying_pixel_prob: float = 0.2
    edge_dropout_prob: float = 0.5

    def __post_init__(self) -> None:
        if self.sigma_const_m < 0 or self.sigma_quad_per_m < 0:
            raise ValueError("sigma_const_m and sigma_quad_per_m must be >= 0")
        for name in ("dropout_prob", "flying_pixel_prob", "edge_dropout_prob"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise ValueError(
                    f"{name} must be a probability in [0, 1], got {getattr(self, name)}"
                )
        if not 0.0 <= self.grazing_start_deg < self.grazing_full_deg <= 90.0:
            raise ValueError(
                "need 0 <= grazing_start_deg < grazing_full_deg <= 90, got "
                f"{self.grazing_start_deg}, {self.grazing_full_deg}"
            )
        if not self.edge_jump_m > 0:
            raise ValueError(f"edge_jump_m must be positive metres, got {self.edge_jump_m}")

    def sigma(self, range_m: NDArray[np.floating]) -> NDArray[np.floating]:
        """Standard deviation (m) of the range noise at range ``range_m`` (m)."""
        return self.sigma_const_m + self.sigma_quad_per_m * np.square(range_m)


@dataclass(frozen=True)
class CalibrationErrorConfig:
    """Size of each camera's extrinsic calibration error."""

    translation_m: float = 0.0025
    rotation_deg: float = 0.4

    def __post_init__(self) -> None:
        if self.translation_m < 0 or self.rotation_deg < 0:
            raise ValueError("calibration error sizes must be >= 0")


# ---- time-of-flight noise ---------------------------------------------------------------------


def neighbourhood_extremes(depth: Array) -> tuple[Array, Array]:
    """Smallest and largest valid (> 0) depth in each pixel's 3 x 3 neighbourhood (itself
    included); NaN where the neighbourhood holds no valid depth."""
    h, w = depth.shape
    padded = np.full((h + 2, w + 2), np.nan)
    padded[1:-1, 1:-1] = np.where(depth > 0, depth, np.nan)
    lo = np.full((h, w), np.nan)
    hi = np.full((h, w), np.nan)
    for dv in range(3):
        for du in range(3):
            view = padded[dv : dv + h, du : du + w]
            lo = np.fmin(lo, view)
            hi = np.fmax(hi, view)
    return lo, hi


def incidence_cosine(points_cam: Array, valid: NDArray[np.bool_]) -> Array:
    """|cos| of the angle between each pixel's ray and the surface normal, (H, W).

    The normal is the cross product of the central differences of the back-projected points
    along the rows and the columns. Where a neighbour is invalid the normal is unknown and the
    cosine is set to 1 (such pixels are handled as edges, not as grazing surfaces).
    """
    h, w = valid.shape
    cos = np.ones((h, w))
    du = points_cam[1:-1, 2:] - points_cam[1:-1, :-2]
    dv = points_cam[2:, 1:-1] - points_cam[:-2, 1:-1]
    normal = np.cross(du, dv)
    ray = points_cam[1:-1, 1:-1]
    denom = np.linalg.norm(normal, axis=-1) * np.linalg.norm(ray, axis=-1)
    inner = (
        valid[1:-1, 1:-1] & valid[1:-1, 2:] & valid[1:-1, :-2] & valid[2:, 1:-1] & valid[:-2, 1:-1]
    )
    inner &= denom > 0
    c = np.abs(np.einsum("ijk,ijk->ij", normal, ray)) / np.where(inner, denom, 1.0)
    cos[1:-1, 1:-1] = np.where(inner, c, 1.0)
    return cos


def grazing_ramp(cos_theta: Array, start_deg: float, full_deg: float) -> Array:
    """0 for incidence angles below ``start_deg``, 1 above ``full_deg``, linear in between."""
    theta = np.rad2deg(np.arccos(np.clip(cos_theta, 0.0, 1.0)))
    return np.clip((theta - start_deg) / (full_deg - start_deg), 0.0, 1.0)


@dataclass(frozen=True)
class TofNoiseResult:
    """A noisy depth image and what happened to each pixel (all (H, W))."""

    depth_m: NDArray[np.float32]
    edge: NDArray[np.bool_]
    flying: NDArray[np.bool_]
    dropped: NDArray[np.bool_]


def apply_tof_noise(
    depth_m: NDArray[np.floating], K: Array, config: TofNoiseConfig, rng: np.random.Generator
) -> TofNoiseResult:
    """Time-of-flight errors on a clean planar-depth image (see the module docstring).

    Args:
        depth_m: (H, W) clean depth, metres, 0 = invalid.
        K: (3, 3) intrinsics (for the rays and the incidence angle).
        config: noise parameters.
        rng: the only source of randomness; four (H, W) draws per call.
    """
    depth = np.asarray(depth_m, dtype=np.float64)
    valid = depth > 0
    shape = depth.shape
    gauss = rng.standard_normal(shape)
    u_fly = rng.random(shape)
    mix = rng.random(shape)
    u_drop = rng.random(shape)

    near, far = neighbourhood_extremes(depth)
    edge = valid & (far - near > config.edge_jump_m)
    flying = edge & (u_fly < config.flying_pixel_prob)
    z = np.where(flying, near + mix * (far - near), depth)

    ray_len = np.linalg.norm(backproject(np.ones(shape), K), axis=-1)  # range per metre of z
    r = z * ray_len
    z = z * (1.0 + config.sigma(r) * gauss / np.where(valid, r, 1.0))

    cos = incidence_cosine(backproject(depth, K), valid)
    base = config.dropout_prob
    ramp = grazing_ramp(cos, config.grazing_start_deg, config.grazing_full_deg)
    # Across a discontinuity the finite-difference normal is meaningless: edges follow their
    # own rule, not the grazing one.
    p_drop = np.where(edge, base, base + (1.0 - base) * ramp)
    p_drop = np.where(edge & ~flying, max(base, config.edge_dropout_prob), p_drop)
    dropped = valid & (u_drop < p_drop)
    keep = valid & ~dropped & (z > 0)
    out = np.where(keep, z, 0.0).astype(np.float32)
    return TofNoiseResult(out, edge, flying & keep, dropped)


# ---- DexNet-style noise (VGN/GIGA's clutter removal) ------------------------------------------


@dataclass(frozen=True)
class DexNoiseConfig:
    """GIGA's ``apply_dex_noise`` (``src/vgn/utils/misc.py``; the values are its defaults):
    the whole image times one gamma-distributed factor (shape ``gamma_shape``, scale
    ``gamma_scale``: mean 1, sd 3 %), then, with probability ``gp_rate``, Gaussian noise of
    sd ``gp_sigma_m`` drawn on a grid ``gp_scale`` times coarser than the image and upsampled
    bilinearly (a smooth random warp of the depth)."""

    gamma_shape: float = 1000.0
    gamma_scale: float = 0.001
    gp_sigma_m: float = 0.005
    gp_scale: float = 4.0
    gp_rate: float = 0.5

    def __post_init__(self) -> None:
        if not (self.gamma_shape > 0 and self.gamma_scale > 0 and self.gp_scale >= 1):
            raise ValueError("dex noise: gamma_shape, gamma_scale > 0 and gp_scale >= 1")
        if self.gp_sigma_m < 0 or not 0.0 <= self.gp_rate <= 1.0:
            raise ValueError("dex noise: gp_sigma_m >= 0 and gp_rate in [0, 1]")


def apply_dex_noise(
    depth_m: NDArray[np.floating], config: DexNoiseConfig, rng: np.random.Generator
) -> NDArray[np.float32]:
    """The depth image with :class:`DexNoiseConfig`'s noise on its valid (> 0) pixels; invalid
    pixels stay 0 (theirs adds the warp to them too, where their TSDF ignores it as too near).
    Always the same draws per image: one gamma, one uniform, one coarse grid."""
    from scipy.ndimage import zoom

    depth = np.asarray(depth_m, dtype=np.float64)
    h, w = depth.shape
    valid = depth > 0
    out = depth * rng.gamma(config.gamma_shape, config.gamma_scale)
    warp = rng.uniform() < config.gp_rate
    gh, gw = int(h / config.gp_scale), int(w / config.gp_scale)
    grid = rng.standard_normal((gh, gw)) * config.gp_sigma_m
    if warp:
        up = zoom(grid, (h / gh, w / gw), order=1, mode="grid-constant", grid_mode=True)
        out = out + up[:h, :w]
    return np.where(valid, out, 0.0).astype(np.float32)


# ---- calibration error ------------------------------------------------------------------------


def _unit_vectors(n: int, rng: np.random.Generator) -> Array:
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def rotation_about(axis: Array, angle_rad: float) -> Array:
    """(3, 3) rotation by ``angle_rad`` about the unit ``axis`` (Rodrigues)."""
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.eye(3) + np.sin(angle_rad) * k + (1.0 - np.cos(angle_rad)) * (k @ k)


def calibration_errors(
    n_cameras: int, config: CalibrationErrorConfig, rng: np.random.Generator
) -> Array:
    """(n_cameras, 4, 4) rigid errors ``E`` (``T_believed = T_true @ E``), each rotating by
    exactly ``rotation_deg`` about a random axis and translating by exactly ``translation_m``
    in a random direction."""
    axes = _unit_vectors(n_cameras, rng)
    dirs = _unit_vectors(n_cameras, rng)
    errors = np.tile(np.eye(4), (n_cameras, 1, 1))
    for i in range(n_cameras):
        errors[i, :3, :3] = rotation_about(axes[i], np.deg2rad(config.rotation_deg))
        errors[i, :3, 3] = config.translation_m * dirs[i]
    return errors
