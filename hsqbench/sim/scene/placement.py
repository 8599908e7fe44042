"""Isolated and packed placement: objects upright (or resting) apart inside the workspace."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hsqbench.sim.objects import ObjectLike, resolve_object
from hsqbench.sim.scene.config import PlacementConfig, SceneConfig, load_scene_config
from hsqbench.sim.scene.footprint import footprint_corners, object_footprint, rectangles_overlap
from hsqbench.sim.scene.info import KINDS


def draw_rests(
    assets: Sequence[ObjectLike], placement: PlacementConfig, rng: np.random.Generator
) -> list[tuple[int, np.ndarray]] | None:
    """Each object's resting pose (index, rotation) drawn by probability; None when upright
    (nothing is drawn then, so upright scenes keep the random stream they always had)."""
    if placement.pose == "upright":
        return None
    from hsqbench.assets.resting import resting_poses

    out = []
    for asset in assets:
        poses = resting_poses(asset, placement.min_resting_probability)
        k = poses.draw(rng)
        out.append((k, poses.rotations[k]))
    return out


class PlacementError(ValueError):
    """The objects cannot be placed apart inside the workspace (with the given random stream)."""


def _inside(corners: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    return bool(np.all(corners >= lo) and np.all(corners <= hi))


def place_objects(
    extents_xy: Sequence[np.ndarray],
    names: Sequence[str],
    workspace_lo: np.ndarray,
    workspace_hi: np.ndarray,
    placement: PlacementConfig,
    rng: np.random.Generator,
) -> list[tuple[np.ndarray, float]]:
    """Positions (x, y) and yaws (rad) of footprints that lie inside the workspace and keep
    ``margin_m`` from each other. Larger footprints are placed first.

    Raises:
        PlacementError: when an object cannot fit the workspace at any yaw, or no layout was
            found within the configured tries (names the objects and the areas involved).
    """
    ext = [np.asarray(e, dtype=float) for e in extents_xy]
    size = workspace_hi - workspace_lo
    for name, e in zip(names, ext, strict=True):
        if min(e) > min(size) or max(e) > np.hypot(*size):
            raise PlacementError(
                f"object {name!r} (footprint {e[0]:.3f} x {e[1]:.3f} m) cannot fit the "
                f"{size[0]:.2f} x {size[1]:.2f} m workspace; enlarge workspace.size_m in scene.yaml"
            )
    order = np.argsort([-e[0] * e[1] for e in ext], kind="stable")
    for _ in range(placement.max_scene_attempts):
        placed: dict[int, tuple[np.ndarray, float, np.ndarray]] = {}
        for i in order:
            for _ in range(placement.max_tries_per_object):
                yaw = float(rng.uniform(-np.pi, np.pi))
                xy = rng.uniform(workspace_lo, workspace_hi)
                corners = footprint_corners(ext[i], xy, yaw)
                if not _inside(corners, workspace_lo, workspace_hi):
                    continue
                if any(
                    rectangles_overlap(corners, other, placement.margin_m)
                    for _, _, other in placed.values()
                ):
                    continue
                placed[int(i)] = (xy, yaw, corners)
                break
            else:
                break
        if len(placed) == len(ext):
            return [(placed[i][0], placed[i][1]) for i in range(len(ext))]
    area = sum(float(e[0] * e[1]) for e in ext)
    raise PlacementError(
        f"could not place {list(names)} without contact in the {size[0]:.2f} x {size[1]:.2f} m "
        f"workspace after {placement.max_scene_attempts} attempts (footprints cover "
        f"{area:.3f} m^2 of {size[0] * size[1]:.3f} m^2 before the {placement.margin_m} m margin); "
        "choose fewer or smaller objects, or enlarge the workspace"
    )


def draw_object_names(kind: str, n_objects: int, rng: np.random.Generator) -> list[str]:
    """Names drawn from the paper's 15 YCB objects (those the library has): one for
    ``isolated``, ``n_objects`` different ones for ``packed`` or ``pile``. The paper's set, not the whole
    library: its packed draws are known to fit the workspace (a plate, a skillet lid and a chain
    with two others often do not)."""
    from hsqbench.assets.library import ycb_names
    from hsqbench.experiment.config import YCB_OBJECTS

    if kind not in KINDS:
        raise ValueError(f"unknown scene kind {kind!r}; known: {list(KINDS)}")
    known = set(ycb_names())
    pool = [n for n in YCB_OBJECTS if n in known]
    count = 1 if kind == "isolated" else n_objects
    if count > len(pool):
        raise ValueError(f"cannot draw {count} different objects from {len(pool)}: {pool}")
    return [pool[i] for i in rng.choice(len(pool), count, replace=False)]


def scene_object_count(kind: str, cfg: SceneConfig) -> int:
    """How many objects a scene of ``kind`` draws when none are given."""
    if kind not in KINDS:
        raise ValueError(f"unknown scene kind {kind!r}; known: {list(KINDS)}")
    return {"isolated": 1, "packed": cfg.placement.n_packed, "pile": cfg.pile.n_objects}[kind]


def resolve_scene_objects(
    kind: str,
    objects: Sequence[str | ObjectLike] | str | ObjectLike | None,
    n_objects: int,
    rng: np.random.Generator,
) -> list[ObjectLike]:
    """The scene's objects: those given, or ``n_objects`` drawn from ``rng``; checked for the
    kind (one object for isolated) and for duplicates."""
    if kind not in KINDS:
        raise ValueError(f"unknown scene kind {kind!r}; known: {list(KINDS)}")
    chosen: list[str | ObjectLike]
    if objects is None:
        chosen = list(draw_object_names(kind, n_objects, rng))
    elif isinstance(objects, str) or not isinstance(objects, Sequence):
        chosen = [objects]
    else:
        chosen = list(objects)
    if kind == "isolated" and len(chosen) != 1:
        raise ValueError(f"an isolated scene has one object, got {len(chosen)}")
    if not chosen:
        raise ValueError(f"a {kind} scene needs at least one object")
    names = [o if isinstance(o, str) else o.name for o in chosen]
    if len(set(names)) != len(names):
        raise ValueError(f"objects must be different, got {names}")
    return [resolve_object(o) for o in chosen]


def layout_objects(
    assets: Sequence[ObjectLike],
    cfg: SceneConfig,
    rng: np.random.Generator,
    rests: Sequence[tuple[int, np.ndarray]] | None = None,
) -> list[tuple[np.ndarray, float]]:
    """Object origins (x, y) and yaws (rad) with the footprints apart inside the workspace.

    The placement of :func:`build_scene`, without a MuJoCo model: oriented footprints from the
    collision hulls (:func:`object_footprint`, each turned by its resting pose in ``rests``),
    then :func:`place_objects`.

    Raises:
        PlacementError: no layout was found (see :func:`place_objects`).
    """
    ws = cfg.workspace
    lo = np.asarray(ws.centre_xy_m) - np.asarray(ws.size_m) / 2
    hi = np.asarray(ws.centre_xy_m) + np.asarray(ws.size_m) / 2
    rotations = [None] * len(assets) if rests is None else [r for _, r in rests]
    prints = [object_footprint(a, r) for a, r in zip(assets, rotations, strict=True)]
    rect_poses = place_objects(
        [f.extents_xy for f in prints], [a.name for a in assets], lo, hi, cfg.placement, rng
    )
    return [f.object_pose(xy, yaw) for f, (xy, yaw) in zip(prints, rect_poses, strict=True)]


def packed_placeable(
    objects: Sequence[str | ObjectLike], seed: int, scene_config: SceneConfig | None = None
) -> bool:
    """Whether ``build_scene("packed", objects, seed)`` can place ``objects`` apart.

    Exact, not an estimate: it runs the same seeded placement as :func:`build_scene` (the
    placement is a rejection sampler, so the answer belongs to this seed), from the footprints
    and the workspace only, without compiling a model (milliseconds; footprints are cached).
    Unknown or duplicate objects still raise ``ValueError``.
    """
    cfg = scene_config or load_scene_config()
    rng = np.random.default_rng(seed)
    assets = resolve_scene_objects("packed", objects, cfg.placement.n_packed, rng)
    rests = draw_rests(assets, cfg.placement, rng)
    try:
        layout_objects(assets, cfg, rng, rests)
    except PlacementError:
        return False
    return True
