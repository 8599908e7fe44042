"""Stable resting poses of an object on a plane, with the probability of each.

A resting pose is the rotation that turns the object frame so that the object lies on one face
of its convex hull, the centre of mass above that face. Its probability is the share of random
drops that end on that face (the solid angle of the face's region of the hull, as seen from the
centre of mass, computed by :func:`trimesh.poses.compute_stable_poses` with no noise).

The hull is that of the collision hulls (what MuJoCo simulates), and the centre of mass the
asset's. Poses are cached as ``resting_poses.json`` beside the built asset (``build_dir``),
written atomically on first use, so scenes draw them without recomputing.
"""

from __future__ import annotations

import functools
import json
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

FILE_NAME = "resting_poses.json"
#: Version of the file's content: bump it when the computation changes so caches are redone.
VERSION = 1


@dataclass(frozen=True, eq=False)
class RestingPoses:
    """Resting poses of one object, most probable first.

    Attributes:
        rotations: (K, 3, 3) rotations from the object frame to the resting frame (z up).
        probabilities: (K,) probabilities, summing to 1.
    """

    rotations: np.ndarray
    probabilities: np.ndarray

    def __post_init__(self) -> None:
        if len(self.rotations) == 0 or len(self.rotations) != len(self.probabilities):
            raise ValueError("resting poses need one probability per rotation, at least one")

    def draw(self, rng: np.random.Generator) -> int:
        """The index of a pose drawn by probability."""
        return int(rng.choice(len(self.probabilities), p=self.probabilities))


def compute_resting_poses(
    vertices: np.ndarray, com: np.ndarray, min_probability: float = 0.0
) -> RestingPoses:
    """Resting poses of the convex hull of ``vertices`` about the centre of mass ``com``.

    Poses less likely than ``min_probability`` are dropped (edge-on slivers of a hull facet that
    a real drop would not end on) and the rest renormalised.
    """
    import trimesh

    hull = trimesh.Trimesh(np.asarray(vertices, float)).convex_hull
    transforms, probs = trimesh.poses.compute_stable_poses(
        hull, center_mass=np.asarray(com, float), sigma=0.0, n_samples=1
    )
    probs = np.asarray(probs, float)
    keep = probs >= min_probability
    if not keep.any():
        keep = probs == probs.max()
    rotations = np.asarray(transforms, float)[keep, :3, :3]
    probs = probs[keep] / probs[keep].sum()
    order = np.argsort(-probs, kind="stable")
    return RestingPoses(rotations[order], probs[order])


def resting_poses(asset: Any, min_probability: float = 0.0) -> RestingPoses:
    """The asset's resting poses: from its cache file, else computed (and cached when the asset
    has a ``build_dir``)."""
    paths = tuple(str(p) for p in asset.collision_meshes)
    if not paths:
        raise ValueError(f"{asset.name}: no collision meshes to rest on")
    build_dir = getattr(asset, "build_dir", None)
    return _cached(
        paths,
        tuple(os.stat(p).st_mtime_ns for p in paths),
        tuple(float(c) for c in asset.com),
        None if build_dir is None else str(build_dir),
        float(min_probability),
    )


@functools.lru_cache(maxsize=128)
def _cached(
    paths: tuple[str, ...],
    mtimes_ns: tuple[int, ...],
    com: tuple[float, ...],
    build_dir: str | None,
    min_probability: float,
) -> RestingPoses:
    key = {"version": VERSION, "com": list(com), "min_probability": min_probability}
    cache = None if build_dir is None else Path(build_dir) / FILE_NAME
    if cache is not None and cache.exists():
        stored = json.loads(cache.read_text())
        if stored.get("key") == key:
            return RestingPoses(
                np.asarray(stored["rotations"], float), np.asarray(stored["probabilities"], float)
            )
    import trimesh

    vertices = np.concatenate(
        [trimesh.load(p, force="mesh", process=False).vertices for p in paths]
    )
    poses = compute_resting_poses(vertices, np.asarray(com), min_probability)
    if cache is not None:
        _write_atomic(
            cache,
            {
                "key": key,
                "rotations": poses.rotations.tolist(),
                "probabilities": poses.probabilities.tolist(),
            },
        )
    return poses


def _write_atomic(path: Path, record: dict[str, Any]) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            json.dump(record, f)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
