"""VGN's and GIGA's grasp detection on one cube's network volumes (numpy and scipy only).

As both papers' code does it, in order: smooth the quality volume with a Gaussian; zero it
where a grasp centre cannot be (not within ``free_dilation_voxels`` of observed free space, or
inside an object, both read from the TSDF), where the predicted width is outside the limits,
and within the bounds of the cube's faces; drop qualities below ``low_quality``, then below the
threshold (or, with ``force_detection`` and nothing above it, keep only the best); keep the
local maxima of a ``max_filter_voxels`` window; rank by quality.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from hsqbench.planner.learned.volumetric_config import DetectionConfig

#: scipy's Gaussian filter reads ``int(truncate * sigma + 0.5)`` voxels either side (truncate 4).
_TRUNCATE = 4.0


@dataclass(frozen=True)
class Detections:
    """Grasps found in one cube, best first.

    Attributes:
        index: (M, 3) voxel indices of the grasp centres.
        quality: (M,) smoothed quality in [0, 1].
    """

    index: NDArray[np.int64]
    quality: NDArray[np.float64]


def valid_centres(tsdf_input: NDArray, cfg: DetectionConfig) -> NDArray[np.bool_]:
    """Voxels where a grasp centre may lie: observed free space near a surface, dilated by
    ``free_dilation_voxels`` but never into an object (``tsdf_input``: the network's input)."""
    outside = tsdf_input > cfg.surface_tsdf
    inside = (tsdf_input > cfg.empty_tsdf) & (tsdf_input < cfg.surface_tsdf)
    if cfg.free_dilation_voxels == 0:
        return outside
    return ndimage.binary_dilation(
        outside, iterations=cfg.free_dilation_voxels, mask=~inside
    ).astype(bool)


def smoothing_support(valid: NDArray[np.bool_], cfg: DetectionConfig) -> NDArray[np.bool_]:
    """Voxels whose quality the smoothing reads at ``valid`` voxels: the only ones a network
    needs to evaluate (the detection is then the same as on the whole volume)."""
    radius = int(_TRUNCATE * cfg.smoothing_sigma_voxels + 0.5)
    if radius == 0:
        return valid.copy()
    return ndimage.maximum_filter(valid, size=2 * radius + 1, mode="constant", cval=False)


def bound_voxels(cfg: DetectionConfig, voxel_m: float) -> tuple[int, int, int]:
    """Voxels cut at the cube's lower/upper x and y faces and its floor (the codes' floors)."""
    return tuple(int(b / voxel_m) for b in cfg.bound_m)  # type: ignore[return-value]


def detect(
    quality: NDArray,
    width_voxels: NDArray,
    valid: NDArray[np.bool_],
    cfg: DetectionConfig,
    voxel_m: float,
) -> Detections:
    """Grasps of one cube (module notes).

    Args:
        quality: (X, Y, Z) raw network quality (any value where ``smoothing_support`` is False).
        width_voxels: (X, Y, Z) predicted opening, voxels.
        valid: (X, Y, Z) from :func:`valid_centres`.
        cfg: the detection settings.
        voxel_m: voxel edge, metres (for the bounds).
    """
    q = np.asarray(quality, dtype=np.float64)
    if cfg.smoothing_sigma_voxels > 0:
        q = ndimage.gaussian_filter(
            q, sigma=cfg.smoothing_sigma_voxels, mode="nearest", truncate=_TRUNCATE
        )
    else:
        q = q.copy()
    q[~valid] = 0.0
    q[(width_voxels < cfg.min_width_voxels) | (width_voxels > cfg.max_width_voxels)] = 0.0
    bx, by, bz = bound_voxels(cfg, voxel_m)
    if bx:
        q[:bx] = 0.0
        q[-bx:] = 0.0
    if by:
        q[:, :by] = 0.0
        q[:, -by:] = 0.0
    q[:, :, :bz] = 0.0
    q[q < cfg.low_quality] = 0.0
    best_only = cfg.force_detection and not np.any(q >= cfg.quality_threshold)
    if not best_only:
        q[q < cfg.quality_threshold] = 0.0
    peaks = q == ndimage.maximum_filter(q, size=cfg.max_filter_voxels)
    index = np.argwhere(peaks & (q > 0))
    scores = q[tuple(index.T)]
    order = np.argsort(-scores, kind="stable")
    if best_only:
        order = order[:1]
    return Detections(index=index[order].astype(np.int64), quality=scores[order])
