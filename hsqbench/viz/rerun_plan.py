"""What :meth:`RerunRecorder.on_plan <hsqbench.viz.rerun_recorder.RerunRecorder.on_plan>` logs:
hidden superquadrics, candidates by fate and the best grasps (entity paths in
:mod:`hsqbench.viz.rerun_recorder`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.viz.colors import OTHER_REASON_COLOR, REASON_COLORS, score_colors
from hsqbench.viz.config import ViewerConfig
from hsqbench.viz.gripper_outline import gripper_outline


def _evenly(indices: NDArray[np.int64], cap: int) -> NDArray[np.int64]:
    """At most ``cap`` of ``indices``, evenly spread (first and last kept)."""
    if indices.size <= cap:
        return indices
    return indices[np.linspace(0, indices.size - 1, cap).round().astype(np.int64)]


def _best_scores(plan: Any, n_hidden: int) -> NDArray[np.float64]:
    """Best surviving score of each hidden superquadric (NaN: none survived)."""
    best = np.full(n_hidden, np.nan)
    cands = getattr(plan, "candidates", None)
    if cands is not None and len(cands):
        kept = np.flatnonzero(cands.kept & np.isfinite(cands.scores))
        src = np.asarray(cands.lines.source)[cands.line_index[kept]]
        ok = (src >= 0) & (src < n_hidden)
        np.fmax.at(best, src[ok], cands.scores[kept][ok])
        return best
    for g in plan.grasps:
        if 0 <= g.source < n_hidden:
            best[g.source] = np.fmax(best[g.source], g.score)
    return best


def _log_superquadrics(
    rec: Any,
    rr: Any,
    cfg: ViewerConfig,
    hidden: list[Any],
    best: NDArray[np.float64],
    cloud: NDArray[np.float64] | None,
) -> None:
    """Each hidden superquadric as a mesh coloured by its best score, with its inliers."""
    colors = score_colors(best)
    for i, h in enumerate(hidden):
        sq = getattr(h, "superquadric", h)
        verts, faces = sq.to_mesh(cfg.superquadric_mesh_quarter)
        path = f"world/planner/superquadrics/{i}"
        rec.log(
            path,
            rr.Mesh3D(
                vertex_positions=verts.astype(np.float32),
                triangle_indices=faces.astype(np.uint32),
                vertex_normals=sq.normals(verts).astype(np.float32),
                albedo_factor=colors[i],
            ),
            rr.AnyValues(
                eps1=float(sq.eps1),
                eps2=float(sq.eps2),
                scale_m=np.asarray(sq.scale, float).tolist(),
                alpha_m=float(getattr(h, "alpha", np.nan)),
                beta=float(getattr(h, "beta", np.nan)),
                best_score=float(best[i]),
            ),
        )
        inliers = getattr(h, "inliers", None)
        if inliers is not None and cloud is not None:
            idx = _evenly(np.asarray(inliers, dtype=np.int64), cfg.max_inliers)
            pts = cloud[idx]
            rec.log(
                f"{path}/inliers",
                rr.Points3D(pts, colors=colors[i], radii=cfg.inlier_radius_m),
            )


def _log_candidates(rec: Any, rr: Any, cfg: ViewerConfig, cands: Any) -> None:
    """Candidates as arrows ending at P_G: ``kept`` coloured by score, the others by rule."""
    positions = cands.positions
    vectors = cfg.candidate_length_m * cands.rotations[:, :, 2]
    reasons = np.asarray(cands.rejected_by)
    for reason in np.unique(reasons):
        idx = _evenly(np.flatnonzero(reasons == reason), cfg.max_candidates)
        if reason == "":
            cls, colors = "kept", score_colors(cands.scores[idx])
        else:
            cls = str(reason)
            color = REASON_COLORS.get(cls, OTHER_REASON_COLOR)
            colors = np.broadcast_to(np.array(color, np.uint8), (idx.size, 4))
        rec.log(
            f"world/planner/candidates/{rr.escape_entity_path_part(cls)}",
            rr.Arrows3D(
                origins=positions[idx] - vectors[idx],
                vectors=vectors[idx],
                colors=colors,
                radii=cfg.candidate_radius_m,
            ),
        )


def _log_plan_geometry(rec: Any, rr: Any, cfg: ViewerConfig, plan: Any) -> None:
    """A plan's candidates (if any) and its planner's own surface points (if any: the vgn and
    giga planners' TSDF zero crossings, ``PlanResult.surface_points``)."""
    cands = getattr(plan, "candidates", None)
    if cands is not None and len(cands):
        _log_candidates(rec, rr, cfg, cands)
    surface = getattr(plan, "surface_points", None)
    if surface is not None and len(surface):
        rec.log("world/planner/surface", rr.Points3D(surface, radii=cfg.cloud_radius_m))


def _log_top_grasps(rec: Any, rr: Any, cfg: ViewerConfig, gripper: Any, grasps: Any) -> None:
    """Outlines of the best ``cfg.top_grasps`` grasps, coloured and labelled by score."""
    top = [grasps[k] for k in range(min(cfg.top_grasps, len(grasps)))]
    if top:
        strips, strip_colors, labels = [], [], []
        for k, g in enumerate(top):
            lines = gripper_outline(gripper, g.position, g.rotation, g.width, cfg.stem_length_m)
            strips += lines
            strip_colors += [score_colors([g.score])[0]] * len(lines)
            labels += [f"#{k} {g.score:.3f}"] + [""] * (len(lines) - 1)
        rec.log(
            "world/planner/top_grasps",
            rr.LineStrips3D(
                strips, colors=strip_colors, labels=labels, radii=cfg.outline_radius_m / 2
            ),
        )
