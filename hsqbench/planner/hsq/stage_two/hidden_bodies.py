"""Elimination rule 6 (addition): the hand must not enter the hidden superquadrics.

The collision and sweep rules see only the cloud, i.e. what the cameras saw. A body behind what
they saw (behind a handle that hides it from the cameras, the far half of a hollow part) holds
no points, and a finger may be planned into it. Stage one's hidden superquadrics model that
body. Their surfaces, shrunk by ``body_margin_m`` (fit error) and sampled every
``body_spacing_m``, become obstacle points for the open fingers and the palm's approach path,
like cloud points, except where a camera saw through them: a sample in front of the surface a
camera measured along its ray (by more than ``body_carve_margin_m``) lies in free space the
camera saw, so the superquadric overshoots the object there, and the sample is dropped (space
carving on the cloud's depth).

The rule needs the cameras' positions: without them a fit that overshoots into free space
cannot be told from a hidden body, and the planner skips the rule (``plan_from_hidden``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import minimum_filter

from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.hsq.config import GraspConfig
from hsqbench.superquadric.geometry import Superquadric

#: Cells of one camera's depth buffer at most; a larger footprint gets coarser cells.
_MAX_CELLS = 4_000_000


def shrunk_surface_samples(
    superquadrics: Sequence[Superquadric], config: GraspConfig
) -> NDArray[np.float64]:
    """(M, 3): the surfaces of ``superquadrics`` with every semi-axis shortened by
    ``body_margin_m``, sampled every ``body_spacing_m`` and thinned to one sample per voxel of
    that size (overlapping fits give one set). A superquadric whose shrunk semi-axes are not
    all over half the spacing (thinner than ``2 body_margin_m + body_spacing_m``, 11 mm: a wall,
    which the cameras see) gives none: its shrunk body would be thinner than one spacing."""
    margin, spacing = config.body_margin_m, config.body_spacing_m
    parts = []
    for sq in superquadrics:
        scale = np.asarray(sq.scale) - margin
        if np.all(scale > 0.5 * spacing):
            shrunk = Superquadric(sq.eps1, sq.eps2, scale, sq.rotation, sq.translation)
            parts.append(shrunk.sample_surface(spacing)[0])
    if not parts:
        return np.zeros((0, 3))
    return voxel_downsample(np.concatenate(parts), spacing).points


def seen_free(
    samples: NDArray,
    cloud: NDArray,
    cameras: NDArray,
    config: GraspConfig,
    support_plane: NDArray | None = None,
) -> NDArray[np.bool_]:
    """(M,): samples some camera saw through, i.e. nearer to it than what it measured along the
    same ray by more than ``body_carve_margin_m``.

    Each camera's measurement is a depth buffer of the cloud: depth along the camera's mean view
    direction, on cells ``body_pixel_m`` wide at the cloud's median depth, each cell the nearest
    depth of itself and its 8 neighbours (a missing pixel or a cell on an edge then counts the
    nearer surface: the strict choice). A ray that meets no cloud point meets the table (the
    cloud has its points removed), or nothing.
    """
    free = np.zeros(samples.shape[0], dtype=bool)
    if samples.shape[0] == 0 or cloud.shape[0] == 0:
        return free
    for cam in np.asarray(cameras, dtype=np.float64).reshape(-1, 3):
        rays_c, rays_s = cloud - cam, samples - cam
        forward = rays_c.mean(axis=0)
        forward /= np.linalg.norm(forward)
        side = np.cross(forward, [0.0, 0.0, 1.0] if abs(forward[2]) < 0.9 else [1.0, 0.0, 0.0])
        side /= np.linalg.norm(side)
        basis = np.stack([side, np.cross(forward, side)])
        z_c, z_s = rays_c @ forward, rays_s @ forward
        ahead = z_c > 1e-6
        if not np.any(ahead):
            continue
        cell = config.body_pixel_m / float(np.median(z_c[ahead]))
        uv_c = (rays_c[ahead] @ basis.T) / z_c[ahead, None]
        uv_s = (rays_s @ basis.T) / np.maximum(z_s, 1e-6)[:, None]
        lo = uv_c.min(axis=0)
        extent = uv_c.max(axis=0) - lo
        cell = max(cell, float(np.sqrt(np.prod(extent + cell) / _MAX_CELLS)))
        shape = np.floor(extent / cell).astype(np.int64) + 1
        ij_c = np.clip(np.floor((uv_c - lo) / cell).astype(np.int64), 0, shape - 1)
        buffer = np.full(tuple(shape), np.inf)
        np.minimum.at(buffer, (ij_c[:, 0], ij_c[:, 1]), z_c[ahead])
        buffer = minimum_filter(buffer, size=3, mode="constant", cval=np.inf)
        ij_s = np.floor((uv_s - lo) / cell).astype(np.int64)
        inside = np.all((ij_s >= 0) & (ij_s < shape), axis=1) & (z_s > 1e-6)
        measured = np.full(samples.shape[0], np.inf)
        measured[inside] = buffer[ij_s[inside, 0], ij_s[inside, 1]]
        if support_plane is not None:
            normal, offset = np.asarray(support_plane[:3]), float(support_plane[3])
            along = rays_s @ normal
            with np.errstate(divide="ignore", invalid="ignore"):
                t = -(cam @ normal + offset) / along
            table = np.where((t > 0.0) & np.isfinite(t), t * z_s, np.inf)
            measured = np.minimum(measured, table)
        free |= (z_s > 1e-6) & (z_s < measured - config.body_carve_margin_m)
    return free


def body_obstacles(
    superquadrics: Sequence[Superquadric],
    cloud: NDArray,
    config: GraspConfig,
    cameras: NDArray | None = None,
    support_plane: NDArray | None = None,
) -> NDArray[np.float64]:
    """(M, 3) obstacle points of rule 6: the shrunk surfaces of ``superquadrics``, less those
    below the table and those a camera saw through (none carved without ``cameras``)."""
    samples = shrunk_surface_samples(superquadrics, config)
    if support_plane is not None and samples.shape[0]:
        plane = np.asarray(support_plane, dtype=np.float64)
        samples = samples[samples @ plane[:3] + plane[3] > 0.0]
    if cameras is not None:
        samples = samples[~seen_free(samples, cloud, cameras, config, support_plane)]
    return samples
