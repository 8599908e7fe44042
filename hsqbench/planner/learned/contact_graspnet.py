"""The ``contact-graspnet`` planner: Contact-GraspNet (Sundermeyer et al., ICRA 2021) in the harness.

A learned 6-DoF grasp detector for the Franka hand, run through the PyTorch port ``cgn-pytorch``
(0.4.3, its pretrained weights ship in the wheel; see :mod:`.network`). Steps:

1. Clean the cloud as hsq and the baselines do (``cleaning:`` of the planner config named by
   ``planner``), so all planners see the same points.
2. Views (``views``): the fused cloud, or each camera's part (``per_camera``: hidden point
   removal from the camera's position, :func:`~.frames.visible_from`; ``per_image``: the points
   its own depth image measured, :func:`~.frames.seen_in_image`, one view as in training);
   grasps of the views are merged.
3. Each view goes to the network in its input frame (``input_frame``: world axes centred on the
   view's mean, as the cgn-pytorch weights were trained, or a look-at camera frame at the camera;
   for the fused cloud that camera sits at the mean of the camera positions), at the network's
   density (``input_voxel_m``), with an optional synthetic table patch (``table_patch_radius_m``;
   grasps whose contact is a patch point are dropped).
4. The network's poses become :class:`~hsqbench.planner.grasp.Grasp` frames (:mod:`.frames`);
   its confidence is the score (factor ``confidence``); grasps under ``confidence_threshold``
   go. The port's width head is unusable, so ``P_G`` and the width come from the cloud along
   each grasp's closing line (``width_source: cloud``, :mod:`.width`), or from the pose as the
   package places it (``network``).
5. By default nothing else is removed (but grasps wider than the hand opens): the network
   predicts collision-free grasps itself. With
   ``eliminate`` the harness's rules (width, support, table, collision, sweep; those of hsq and
   the baselines, same gripper and settings) run on them too.

Each grasp is a closing line with one roll (its own approach), so the result carries a
:class:`~hsqbench.planner.hsq.stage_two.candidates.CandidateSet` like the other planners (viewer, reports).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import PlanningContext, PlanResult, validate_cameras, validate_plane
from hsqbench.planner.base import CleanInput, PlannerBase
from hsqbench.planner.cleaning import CleaningConfig
from hsqbench.planner.downsample import voxel_downsample
from hsqbench.planner.gripper import resolve_gripper
from hsqbench.planner.hsq.config import resolve_config
from hsqbench.planner.hsq.stage_two.candidates import REJECTION_REASONS, CandidateSet, ClosingLines
from hsqbench.planner.hsq.stage_two.elimination import (
    RULE_DESCRIPTIONS,
    approach_openings,
    eliminate,
)
from hsqbench.planner.learned import frames, network, width
from hsqbench.planner.learned.config import (
    ContactGraspNetConfig,
    resolve_contact_graspnet_config,
)

Array = NDArray[np.float64]
FAMILY = "cgn"


def _views(
    cloud: Array, cameras: Array | None, cfg: ContactGraspNetConfig, depth_views=None
) -> list:
    """``(points, camera or None)`` of each view the network gets."""
    if cfg.views == "per_image":
        if not depth_views:
            raise ValueError(
                "contact_graspnet views='per_image' reads each camera's depth image "
                "(PlanningContext.depth_views); the harness's trials pass them, or set "
                "views: fused"
            )
        return [
            (
                cloud[frames.seen_in_image(cloud, v, cfg.image_tolerance_m)],
                np.asarray(v.T_world_camera, dtype=np.float64)[:3, 3],
            )
            for v in depth_views
        ]
    if (cfg.views == "per_camera" or cfg.input_frame == "camera") and cameras is None:
        raise ValueError(
            f"contact_graspnet views={cfg.views!r}, input_frame={cfg.input_frame!r} need "
            "the camera positions (PlanningContext.camera_positions); pass them, or set "
            "views: fused and input_frame: world_centred"
        )
    if cfg.views == "fused":
        return [(cloud, None if cameras is None else cameras.mean(axis=0))]
    return [(cloud[frames.visible_from(cloud, c)], c) for c in cameras]


def _frame(net_in: Array, n_object: int, camera, cfg: ContactGraspNetConfig, up: Array) -> Array:
    """``T_world_frame`` of the network's input: world axes at the mean of everything it is given
    (the table patch included, as the training scenes were centred), or a camera looking at the
    object."""
    if cfg.input_frame == "world_centred":
        return frames.world_centred_frame(net_in)
    return frames.look_at_frame(camera, net_in[:n_object].mean(axis=0), up)


def _network_input(
    points: Array, plane: Array | None, cfg: ContactGraspNetConfig
) -> tuple[Array, int]:
    """The view at the network's density plus the table patch; returns (cloud, n_object)."""
    if cfg.input_voxel_m > 0:
        points = voxel_downsample(points, cfg.input_voxel_m).points
    if plane is None or cfg.table_patch_radius_m == 0:
        return points, points.shape[0]
    patch = frames.table_patch(
        points.mean(axis=0), plane, cfg.table_patch_radius_m, cfg.table_spacing_m
    )
    return np.vstack([points, patch]), points.shape[0]


def predict(
    cloud: Array,
    cameras: Array | None,
    plane: Array | None,
    cfg: ContactGraspNetConfig,
    seed: int,
    elimination_voxel_m: float,
    max_opening_m: float,
    depth_views=None,
) -> tuple[Array, Array, Array, Array]:
    """Network grasps on the object cloud: (``P_G`` (G, 3), rotations (G, 3, 3), widths (G,),
    confidence (G,)), world frame, best confidence first, threshold applied."""
    device = network.resolve_device(cfg.device)
    up = np.array([0.0, 0.0, 1.0]) if plane is None else plane[:3]
    centres, rotations, contacts, conf = [], [], [], []
    for i, (points, camera) in enumerate(_views(cloud, cameras, cfg, depth_views)):
        if points.shape[0] < 64:
            continue  # a camera that sees (almost) nothing of the object
        net_in, n_object = _network_input(points, plane, cfg)
        frame = _frame(net_in, n_object, camera, cfg, up)
        out = network.run_network(
            frames.to_frame(net_in, frame),
            device,
            seed + i,
            cfg.max_input_points,
            cfg.gripper_depth_m,
        )
        keep = (out.input_index < n_object) & (out.confidence >= cfg.confidence_threshold)
        pos, rot = frames.network_to_grasp_frames(
            frames.poses_to_world(out.poses[keep], frame), cfg.gripper_depth_m
        )
        centres.append(pos)
        rotations.append(rot)
        contacts.append(net_in[out.input_index[keep]])
        conf.append(out.confidence[keep])
    if not centres:
        return np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros(0), np.zeros(0)
    conf_all = np.concatenate(conf)
    order = np.argsort(-conf_all, kind="stable")
    if cfg.max_grasps:
        order = order[: cfg.max_grasps]
    centre = np.concatenate(centres)[order]
    rot = np.concatenate(rotations)[order]
    contact = np.concatenate(contacts)[order]
    if cfg.width_source == "cloud":
        coarse = voxel_downsample(cloud, elimination_voxel_m).points
        centre, widths, _ = width.place_on_cloud(
            coarse,
            contact,
            rot[:, :, 0],
            centre,
            cfg.width_ray_radius_m,
            cfg.width_min_m,
            cfg.width_reach_m,
        )
    else:  # the package's placement: one finger at the contact, the hand open (8 cm, rounded)
        widths = np.minimum(2.0 * np.linalg.norm(centre - contact, axis=1), max_opening_m)
    return centre, rot, widths, conf_all[order]


def _set_threads(n: int) -> None:
    if n:
        torch, _, _ = network.import_backend()
        torch.set_num_threads(n)


def plan_contact_graspnet(
    points: ArrayLike,
    config: ContactGraspNetConfig | str | Path | None = None,
    *,
    packed: bool = False,
    support_plane: ArrayLike | None = None,
    seed: int | None = None,
    camera_positions: ArrayLike | None = None,
    name: str = "contact-graspnet",
) -> PlanResult:
    """Contact-GraspNet's grasps on the cleaned cloud (see the module notes).

    Args:
        points: (N, 3) cloud of the object(s), world metres, table removed.
        config: a :class:`ContactGraspNetConfig`, a config name or a YAML path;
            None: ``configs/contact_graspnet.yaml``.
        packed: unused (the network scores grasps the same in clutter).
        support_plane: the table ``(a, b, c, d)``; its normal is "up" for the camera frames
            and it carries the table patch and the table rule.
        seed: the network's subsample and sampling (None = 0).
        camera_positions: (C, 3) camera centres, metres (needed for the camera input frame
            and per-camera views; with ``eliminate`` they waive support at unseen contacts).
        name: the planner name put in the result.

    Raises:
        LearnedExtraMissing: the ``learned`` extra is not installed (the message says how).
        ValueError: a bad cloud, plane, cameras or config.
    """
    del packed  # the network ranks grasps by its confidence alone (no h_delta to drop)
    context = PlanningContext(
        support_plane=support_plane, seed=seed, camera_positions=camera_positions
    )
    return ContactGraspNetPlanner(config, name=name).plan(points, context)


def _no_grasp_reason(n: int, counts: dict[str, int], cfg: ContactGraspNetConfig) -> str:
    if n == 0:
        return (
            "the network predicted no grasp on the object with confidence >= "
            f"{cfg.confidence_threshold:g}"
        )
    removed = ", ".join(f"{r} {counts[r]}" for r in REJECTION_REASONS if counts[r])
    last = next(r for r in reversed(REJECTION_REASONS) if counts[r])
    return (
        f"the rules removed all {n} network grasps ({removed}); the last were removed by "
        f"'{last}' ({RULE_DESCRIPTIONS[last]})"
    )


class ContactGraspNetPlanner(PlannerBase):
    """Contact-GraspNet behind the :class:`~hsqbench.planner.api.Planner` protocol.

    ``eliminate`` (None: the config's) turns the harness's elimination rules on or off; the
    registry's ``contact-graspnet-elim`` is this planner with them on.
    """

    def __init__(
        self,
        config: ContactGraspNetConfig | str | Path | None = None,
        *,
        eliminate: bool | None = None,
        name: str = "contact-graspnet",
    ) -> None:
        network.import_backend()  # fail now, with the install hint, not at the first plan
        cfg = resolve_contact_graspnet_config(config)
        if eliminate is not None:
            cfg = dataclasses.replace(cfg, eliminate=eliminate)
        self.config = cfg
        self.name = name

    def cleaning_config(self) -> CleaningConfig:
        return resolve_config(self.config.planner).cleaning

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """The network's grasps on the cleaned cloud, then (``eliminate``) the shared rules."""
        cfg = self.config
        gcfg = resolve_config(cfg.planner).grasp
        grip = resolve_gripper(gcfg.gripper)
        plane = validate_plane(context.support_plane)
        cameras = validate_cameras(context.camera_positions)
        timings: dict[str, float] = {}
        _set_threads(cfg.torch_threads)

        tick = time.perf_counter()
        seed = 0 if context.seed is None else int(context.seed)
        positions, rotations, widths, conf = predict(
            clean.points,
            cameras,
            plane,
            cfg,
            seed,
            gcfg.elimination_voxel_m,
            grip.max_opening_m,
            context.depth_views,
        )
        timings["network"] = time.perf_counter() - tick

        n = positions.shape[0]
        cands = _candidates(positions, rotations, widths)
        lines = cands.lines
        tick = time.perf_counter()
        remaining = {"synthesised": n}
        if cfg.eliminate:
            remaining = eliminate(
                cands, clean.points, grip, gcfg, plane, seed, camera_positions=cameras
            ).remaining
        else:
            # Only the physical limit: a grasp wider than the hand opens cannot be tried (the
            # network's own placement never is; one found on the cloud can be).
            lines.openings = approach_openings(lines.half_lengths, grip, gcfg)
            cands.rejected_by[widths > grip.max_opening_m] = "width"
            remaining["width"] = int(np.count_nonzero(cands.kept))
        timings["elimination"] = time.perf_counter() - tick

        kept = cands.kept
        cands.scores = np.where(kept, conf, np.nan)
        cands.factors = {"confidence": cands.scores.copy()}
        cands.measures = {"width_m": np.where(kept, widths, np.nan)}
        grasps = cands.ranked()
        counts = cands.counts_by_reason()
        return PlanResult(
            grasps=grasps,
            candidates=cands,
            remaining=remaining,
            removed_by={r: counts[r] for r in REJECTION_REASONS},
            timings=timings,
            reason="" if grasps else _no_grasp_reason(n, counts, cfg),
        )


def _candidates(positions: Array, rotations: Array, widths: Array) -> CandidateSet:
    """The network's grasps as closing lines (no superquadric made them), for the shared rules."""
    n = positions.shape[0]
    lines = ClosingLines(
        centres=positions,
        directions=rotations[:, :, 0],
        approach0=rotations[:, :, 2],
        half_lengths=0.5 * widths,
        source=np.full(n, -1, dtype=np.int64),
        axis=np.full(n, -1, dtype=np.int64),
        family=np.full(n, FAMILY, dtype="<U12"),
    )
    return CandidateSet(lines, np.zeros(1))
