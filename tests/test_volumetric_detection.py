"""The papers' grasp detection on network volumes (numpy only): masks, bounds, width limits,
threshold, local maxima, forced detection."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hsqbench.planner.learned import detection
from hsqbench.planner.learned.volumetric_config import DetectionConfig, VolumetricConfig

VOXEL = 0.0075
N = 40
CFG = DetectionConfig()


def _scene() -> np.ndarray:
    """A network input: a solid block (inside 0.2 near its faces), free space 0.8 above and
    around it within the truncation, 0 beyond."""
    x = np.zeros((N, N, N), dtype=np.float32)
    x[10:30, 10:30, 7:20] = 0.8  # the truncation band around the block
    x[14:26, 14:26, 7:16] = 0.2  # the block's near-surface inside
    x[16:24, 16:24, 7:14] = 0.0  # deep inside: beyond the truncation
    return x


def _volumes(peaks: list[tuple[tuple[int, int, int], float]]):
    quality = np.zeros((N, N, N))
    for (i, j, k), q in peaks:
        # 5 voxels wide: the smoothing (sigma 1 voxel) keeps 97 % of its value.
        quality[max(i - 2, 0) : i + 3, max(j - 2, 0) : j + 3, max(k - 2, 0) : k + 3] = q
    return quality, np.full((N, N, N), 4.0)


def test_valid_centres_are_free_space_near_surfaces_never_inside():
    valid = detection.valid_centres(_scene(), CFG)
    assert valid[12, 12, 18]  # in the free band
    assert not valid[20, 20, 10]  # deep inside the block: 0, but walled off by the inside band
    assert not valid[15, 15, 10]  # the inside band
    assert not valid[2, 2, 30]  # far from any surface
    assert valid[20, 20, 21]  # one voxel above the band (dilation)


def test_detection_keeps_valid_local_maxima_best_first():
    valid = detection.valid_centres(_scene(), CFG)
    quality, width = _volumes([((12, 12, 18), 1.0), ((27, 27, 18), 0.97)])
    found = detection.detect(quality, width, valid, CFG, VOXEL)
    assert found.index.tolist() == [[12, 12, 18], [27, 27, 18]]
    assert found.quality[0] > found.quality[1] > CFG.quality_threshold


@pytest.mark.parametrize(
    ("at", "width", "mask"),
    [
        ((12, 12, 18), 12.0, True),  # wider than 9.33 voxels
        ((12, 12, 18), 1.0, True),  # narrower than 1.33 voxels
        ((20, 20, 10), 4.0, True),  # inside the block (the TSDF's mask)
        ((0, 12, 18), 4.0, False),  # on the cube's lower x face (2 cm bound)
        ((12, 39, 18), 4.0, False),  # on its upper y face
        ((12, 12, 5), 4.0, False),  # within 5.5 cm of its floor
    ],
)
def test_each_rule_removes_a_grasp(at, width, mask):
    # mask False: every voxel may hold a grasp centre, so only the bounds act.
    valid = detection.valid_centres(_scene(), CFG) if mask else np.ones((N, N, N), dtype=bool)
    quality, widths = _volumes([(at, 1.0)])
    widths[:] = width
    forced_off = dataclasses.replace(CFG, force_detection=False)
    assert len(detection.detect(quality, widths, valid, forced_off, VOXEL).index) == 0
    no_rules = dataclasses.replace(forced_off, bound_m=(0.0, 0.0, 0.0))
    kept = detection.detect(
        quality, np.full_like(widths, 4.0), np.ones_like(valid), no_rules, VOXEL
    )
    assert len(kept.index) == 1  # the same peak passes without the rule


def test_below_the_threshold_only_the_forced_best_remains():
    valid = detection.valid_centres(_scene(), CFG)
    quality, width = _volumes([((12, 12, 18), 0.8), ((27, 27, 18), 0.7)])
    forced = detection.detect(quality, width, valid, CFG, VOXEL)
    assert forced.index.tolist() == [[12, 12, 18]]
    off = dataclasses.replace(CFG, force_detection=False)
    assert len(detection.detect(quality, width, valid, off, VOXEL).index) == 0
    low = dataclasses.replace(CFG, quality_threshold=0.65)
    assert len(detection.detect(quality, width, valid, low, VOXEL).index) == 2


def test_neighbouring_peaks_merge_into_one_local_maximum():
    valid = detection.valid_centres(_scene(), CFG)
    quality, width = _volumes([((12, 12, 18), 1.0), ((13, 12, 18), 0.99)])
    assert len(detection.detect(quality, width, valid, CFG, VOXEL).index) == 1


def test_smoothing_support_covers_what_the_filter_reads():
    valid = np.zeros((N, N, N), dtype=bool)
    valid[20, 20, 20] = True
    support = detection.smoothing_support(valid, CFG)
    assert support[16, 24, 20] and not support[15, 20, 20]  # radius 4 voxels at sigma 1
    rng = np.random.default_rng(0)
    quality, width = rng.uniform(0.9, 1.0, (N, N, N)), np.full((N, N, N), 4.0)
    masked = np.where(support, quality, 0.0)
    full = detection.detect(quality, width, valid, CFG, VOXEL)
    part = detection.detect(masked, width, valid, CFG, VOXEL)
    assert full.index.tolist() == part.index.tolist()
    np.testing.assert_allclose(full.quality, part.quality)


def test_config_validates_and_maps_scene_kinds_to_weights():
    cfg = VolumetricConfig()
    assert [cfg.weights_for(s) for s in ("isolated", "packed", "pile", None)] == [
        "packed",
        "packed",
        "pile",
        "packed",
    ]
    with pytest.raises(ValueError, match="packed or pile"):
        VolumetricConfig(weights={"isolated": "packed", "packed": "packed", "pile": "clutter"})
    with pytest.raises(ValueError, match="min_width_voxels"):
        DetectionConfig(min_width_voxels=10.0)
