"""How much room the open fingers left the true object, for recorded isolated attempts.

    python bench/grasp_clearance.py RUN [RUN ...] --planner hsq --graspable
        --outcome collision_on_approach [--min-width-m 0.045] [--sample N] [--out clearance.csv]

Replays each selected attempt (filters as ``bench/replay_attempts.py``) with today's code and,
for the grasp it executed, compares the planner's model with the object's true collision hulls
in the settled pose. Per side of the closing axis (``-`` and ``+`` in the grasp frame): the
modelled contact (half the grasp's width), the open finger's inner face (half the approach
opening), and the true surface's outermost point in the finger's column (within half a finger's
width of the closing plane, from the palm face to the fingertips, and not past the finger's outer
face). ``clearance`` is finger minus
true surface: at or below zero the finger meets the object on its way down. ``fit error`` is the
true surface minus the modelled contact: how far the fit's contact fell short of the object.
``cloud clearance`` is the same clearance to the cleaned cloud the planner saw (NaN: no point in
the column), which the planner's rules could act on.

To pass the truth to the measurement the wrapper declares itself privileged (the trial runner
gives truth only to such planners); it plans with the named planner, which never sees it. The
trial is otherwise the recorded one (same seed, same config), so the replayed outcome matches
the recorded one unless the code changed since.
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))

from replay_attempts import parse_and_select

from hsqbench.planner import get_planner
from hsqbench.planner.base import clean_input
from hsqbench.planner.gripper import GripperModel, resolve_gripper
from hsqbench.sim.trial import load_trial_config, run_isolated_trial

#: Surface samples per object hull set (about one per 2 mm^2 on a cup).
N_SAMPLES = 40_000


class _Recording:
    """Plans with ``inner`` and keeps the last result and the truth it was offered."""

    privileged = True

    def __init__(self, inner: Any) -> None:
        self.inner = inner
        self.result: Any = None
        self.truth: Any = None
        self.points: np.ndarray | None = None

    def plan(self, points: Any, context: Any) -> Any:
        import dataclasses

        self.truth = context.truth
        self.points = np.asarray(points, float)
        self.result = self.inner.plan(points, dataclasses.replace(context, truth=None))
        return self.result


def surface_samples(hulls: list[np.ndarray], rng: np.random.Generator) -> np.ndarray:
    """Points on the hulls' surfaces, uniform by area."""
    from scipy.spatial import ConvexHull

    tris = np.concatenate([h[ConvexHull(h).simplices] for h in hulls])
    area = 0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    pick = rng.choice(len(tris), N_SAMPLES, p=area / area.sum())
    u, v = rng.random((2, N_SAMPLES))
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = tris[pick]
    return t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])


def _reach(grasp: Any, points: np.ndarray, gripper: GripperModel, sign: float) -> float:
    """The outermost of ``points`` on one side in that finger's column, grasp frame, metres."""
    local = (points - grasp.position) @ grasp.rotation
    along = sign * local[:, 0]
    # Beyond the finger's outer face the object does not meet this finger (a wall pinch's inner
    # finger inside a cup, whose far wall lies past it).
    outer = 0.5 * grasp.approach_width + gripper.finger_thickness_m
    column = (
        (np.abs(local[:, 1]) <= 0.5 * gripper.finger_width_m)
        & (local[:, 2] >= -gripper.jaw_length_m)
        & (local[:, 2] <= gripper.fingertip_overhang_m)
        & (along > 0)
        & (along <= outer)
    )
    return float(along[column].max()) if column.any() else float("nan")


def side_measures(
    grasp: Any, surface: np.ndarray, cloud: np.ndarray, gripper: GripperModel
) -> dict[str, float]:
    """Contact, finger, true surface and cloud per side, metres (module docstring)."""
    out = {"width_m": grasp.width, "opening_m": grasp.approach_width}
    for name, sign in (("minus", -1.0), ("plus", 1.0)):
        true = _reach(grasp, surface, gripper, sign)
        out[f"{name}_true_m"] = true
        out[f"{name}_clearance_m"] = 0.5 * grasp.approach_width - true
        out[f"{name}_fit_error_m"] = true - 0.5 * grasp.width
        out[f"{name}_cloud_clearance_m"] = 0.5 * grasp.approach_width - _reach(
            grasp, cloud, gripper, sign
        )
    return out


def main(argv: list[str] | None = None) -> int:
    desc = __doc__.splitlines()[0]
    args, rows = parse_and_select(desc, "CSV of the measures per attempt", argv)
    if rows.empty:
        return 1
    rng = np.random.default_rng(0)
    out = []
    for r in rows.itertuples():
        cfg = load_trial_config(r.trial_config)
        planner = get_planner(r.planner, cfg.planners.for_planner(r.planner))
        wrapper = _Recording(planner)
        obj = r.trial_key.split("/")[3]  # isolated/<planner>/s<seed>/<object>/<index>
        attempt = run_isolated_trial(obj, int(r.seed), wrapper, cfg).attempts[0]
        row = {"trial_key": r.trial_key, "old": r.outcome, "new": attempt.outcome.value}
        grasps = wrapper.result.grasps if wrapper.result is not None else []
        if 0 <= attempt.rank_executed < len(grasps) and wrapper.truth is not None:
            target = wrapper.truth.objects[0]
            surface = surface_samples(list(target.hulls), rng)
            gripper = getattr(planner, "gripper", None) or resolve_gripper("gripper")
            cloud = clean_input(wrapper.points, planner.cleaning_config()).points
            row.update(side_measures(grasps[attempt.rank_executed], surface, cloud, gripper))
        out.append(row)
        if "width_m" in row:
            worst = min(row["minus_clearance_m"], row["plus_clearance_m"])
            short = max(row["minus_fit_error_m"], row["plus_fit_error_m"])
            seen = min(row["minus_cloud_clearance_m"], row["plus_cloud_clearance_m"])
            print(
                f"{r.trial_key}: {r.outcome} -> {row['new']} | width {row['width_m'] * 1e3:.1f}"
                f" opening {row['opening_m'] * 1e3:.1f} mm, least clearance {worst * 1e3:.1f} mm,"
                f" largest fit error {short * 1e3:.1f} mm, least clearance to the cloud"
                f" {seen * 1e3:.1f} mm",
                flush=True,
            )
        else:
            print(f"{r.trial_key}: {r.outcome} -> {row['new']} | no grasp executed", flush=True)
    table = pd.DataFrame(out)
    for (old, new), n in sorted(Counter(zip(table.old, table.new, strict=True)).items()):
        print(f"{old} -> {new}: {n}")
    if "width_m" in table:
        least = table[["minus_clearance_m", "plus_clearance_m"]].min(axis=1) * 1e3
        error = table[["minus_fit_error_m", "plus_fit_error_m"]].max(axis=1) * 1e3
        seen = table[["minus_cloud_clearance_m", "plus_cloud_clearance_m"]].min(axis=1) * 1e3
        print(
            f"least clearance mm: median {least.median():.1f}, under 1 mm {int((least < 1).sum())}"
            f" of {least.notna().sum()}; largest fit error mm: median {error.median():.1f};"
            f" least clearance to the cloud mm: median {seen.median():.1f}, under 3 mm"
            f" {int((seen < 3).sum())}"
        )
    if args.out:
        table.to_csv(args.out, index=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
