"""Depth-sensor error models (hsqbench.sim.sensor_noise), on synthetic depth images."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.sim.camera import backproject, intrinsics_from_fovy
from hsqbench.sim.sensor_noise import (
    CalibrationErrorConfig,
    TofNoiseConfig,
    apply_tof_noise,
    calibration_errors,
    incidence_cosine,
)

QUIET = {"dropout_prob": 0.0, "flying_pixel_prob": 0.0, "edge_dropout_prob": 0.0}


def _plane(z: float, shape=(120, 160)) -> np.ndarray:
    return np.full(shape, z)


def _ray_length(K: np.ndarray, shape) -> np.ndarray:
    h, w = shape
    x = (np.arange(w) - K[0, 2]) / K[0, 0]
    y = (np.arange(h) - K[1, 2]) / K[1, 1]
    return np.sqrt(1.0 + x[None, :] ** 2 + y[:, None] ** 2)


def test_range_noise_matches_sigma_and_grows_with_distance():
    cfg = TofNoiseConfig(**QUIET)
    K = intrinsics_from_fovy(60.0, 160, 120)
    stds = []
    for z in (0.6, 1.5):
        out = apply_tof_noise(_plane(z), K, cfg, np.random.default_rng(3))
        ray = _ray_length(K, (120, 160))
        range_err = (out.depth_m.astype(float) - z) * ray  # noise along the ray
        normalised = range_err / cfg.sigma(z * ray)
        assert np.std(normalised) == pytest.approx(1.0, abs=0.03)
        assert abs(np.mean(normalised)) < 0.03
        stds.append(np.std(range_err))
    assert stds[1] > 2.0 * stds[0]
    assert cfg.sigma(1.0) == pytest.approx(0.0015)


def test_dropout_fraction_is_as_configured_on_a_facing_plane():
    p = 0.05
    cfg = TofNoiseConfig(dropout_prob=p, flying_pixel_prob=0.0, edge_dropout_prob=0.0)
    out = apply_tof_noise(
        _plane(1.0), intrinsics_from_fovy(60.0, 160, 120), cfg, np.random.default_rng(0)
    )
    n = out.depth_m.size
    frac = float(np.mean(out.depth_m == 0))
    assert abs(frac - p) < 4 * np.sqrt(p * (1 - p) / n)
    assert not out.edge.any()


def _tilted_plane(tilt_deg: float, K: np.ndarray, shape) -> np.ndarray:
    """Depth of a plane through (0, 0, 1) whose normal is tilted by ``tilt_deg`` about the
    camera's y axis."""
    h, w = shape
    n = np.array([np.sin(np.deg2rad(tilt_deg)), 0.0, -np.cos(np.deg2rad(tilt_deg))])
    x = (np.arange(w) - K[0, 2]) / K[0, 0]
    y = (np.arange(h) - K[1, 2]) / K[1, 1]
    rays = np.stack(np.broadcast_arrays(x[None, :], y[:, None], np.ones((h, w))), axis=-1)
    return (n @ [0.0, 0.0, 1.0]) / (rays @ n)


def test_dropout_rises_at_grazing_incidence():
    shape = (100, 100)
    K = np.array([[20000.0, 0, 49.5], [0, 20000.0, 49.5], [0, 0, 1]])  # rays nearly parallel
    cfg = TofNoiseConfig(dropout_prob=0.02, flying_pixel_prob=0.0, edge_dropout_prob=0.0)
    fractions = {}
    for tilt in (30.0, 77.5, 88.0):
        depth = _tilted_plane(tilt, K, shape)
        inner = incidence_cosine(backproject(depth, K), depth > 0)[1:-1, 1:-1]
        assert np.allclose(np.rad2deg(np.arccos(inner)), tilt, atol=0.2)  # ray spread 0.15 deg
        out = apply_tof_noise(depth, K, cfg, np.random.default_rng(5))
        fractions[tilt] = float(np.mean(out.depth_m[1:-1, 1:-1] == 0))
    n = 98 * 98
    assert abs(fractions[30.0] - 0.02) < 4 * np.sqrt(0.02 * 0.98 / n)
    expected = 0.02 + 0.98 * 0.5  # halfway up the 70-85 deg ramp
    assert abs(fractions[77.5] - expected) < 4 * np.sqrt(expected * (1 - expected) / n)
    assert fractions[88.0] == 1.0


def test_flying_pixels_lie_between_foreground_and_background():
    depth = np.full((60, 80), 1.2)
    depth[:, :40] = 0.8  # a vertical step: foreground left, background right
    cfg = TofNoiseConfig(
        sigma_const_m=0.0,
        sigma_quad_per_m=0.0,
        dropout_prob=0.0,
        flying_pixel_prob=1.0,
        edge_dropout_prob=0.0,
    )
    out = apply_tof_noise(depth, intrinsics_from_fovy(60.0, 80, 60), cfg, np.random.default_rng(2))
    edge_cols = np.flatnonzero(out.edge.any(axis=0))
    assert set(edge_cols) == {39, 40}
    mixed = out.depth_m[:, 39:41]
    assert np.all((mixed > 0.8) & (mixed < 1.2))
    assert out.flying[:, 39:41].all() and not out.flying[:, :39].any()
    others = np.delete(out.depth_m, [39, 40], axis=1)
    assert np.allclose(others, np.delete(depth, [39, 40], axis=1))


def test_edge_pixels_are_dropped_with_the_edge_probability():
    depth = np.full((200, 80), 1.2)
    depth[:, :40] = 0.8
    cfg = TofNoiseConfig(dropout_prob=0.0, flying_pixel_prob=0.0, edge_dropout_prob=0.5)
    out = apply_tof_noise(depth, intrinsics_from_fovy(60.0, 80, 200), cfg, np.random.default_rng(4))
    frac = float(np.mean(out.depth_m[:, 39:41] == 0))
    assert abs(frac - 0.5) < 4 * np.sqrt(0.25 / 400)
    assert np.all(np.delete(out.depth_m, [39, 40], axis=1) > 0)


def test_invalid_pixels_stay_invalid_and_noise_is_deterministic_per_seed():
    depth = np.full((50, 60), 0.9)
    depth[10:20, 10:20] = 0.0
    K = intrinsics_from_fovy(60.0, 60, 50)
    cfg = TofNoiseConfig()
    a = apply_tof_noise(depth, K, cfg, np.random.default_rng(7)).depth_m
    b = apply_tof_noise(depth, K, cfg, np.random.default_rng(7)).depth_m
    c = apply_tof_noise(depth, K, cfg, np.random.default_rng(8)).depth_m
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)
    assert np.all(a[10:20, 10:20] == 0)
    assert a.dtype == np.float32


def _angle_deg(R: np.ndarray) -> float:
    return float(np.rad2deg(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1))))


def test_calibration_errors_have_the_configured_size_and_are_deterministic():
    cfg = CalibrationErrorConfig(translation_m=0.0025, rotation_deg=0.4)
    e = calibration_errors(2, cfg, np.random.default_rng(11))
    for E in e:
        R = E[:3, :3]
        assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
        assert _angle_deg(R) == pytest.approx(0.4, abs=1e-6)
        assert np.linalg.norm(E[:3, 3]) == pytest.approx(0.0025)
        assert np.allclose(E[3], [0, 0, 0, 1])
    assert not np.allclose(e[0], e[1])  # each camera has its own error
    assert np.array_equal(e, calibration_errors(2, cfg, np.random.default_rng(11)))
    assert not np.allclose(e, calibration_errors(2, cfg, np.random.default_rng(12)))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dropout_prob": 1.5}, "dropout_prob"),
        ({"grazing_start_deg": 80.0, "grazing_full_deg": 70.0}, "grazing"),
        ({"edge_jump_m": 0.0}, "edge_jump_m"),
        ({"sigma_const_m": -1.0}, "sigma"),
    ],
)
def test_tof_config_refuses_bad_values(kwargs, match):
    with pytest.raises(ValueError, match=match):
        TofNoiseConfig(**kwargs)
