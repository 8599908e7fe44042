"""The hsq planner on the benchmark's own clouds of the 15 YCB objects, object by object.

For each object and seed: the isolated scene of that seed (``build_scene("isolated", [name],
seed)``), one observation by the scene's two depth cameras with the configured sensor model
(``configs/perception.yaml``; ``--sensor`` overrides it), then ``plan_grasps`` with the table
plane, the camera centres and the seed (``--planner``: any registered planner, e.g. an
ablation ``hsq-no-sweep`` or the antipodal baseline). Printed per object and seed: the cloud size, the number of grasps, the top
score and width, the planner's CPU time, and either the top grasp's ground-truth check or the
reason for no grasp (``-v``: the candidates left after each rule).

Ground-truth check of the top grasp (no physics; the trial runner executes grasps): the object's
visual mesh, sampled every ~2 mm in its settled pose, against the gripper's boxes
(``configs/gripper.yaml``) at the grasp's approach opening. ``ok`` needs mesh samples between the
pads (something to hold), none inside a finger or the palm (the hand would hit the object), the
object's extent along the closing axis between the pads below the 8 cm stroke, and the fingers
above the table. Failures are named: ``empty``, ``fingers(depth)``, ``palm(depth)`` (the deepest
penetration), ``wide``, ``table``.

Clouds are cached under ``cache_dir()/eval_planner_ycb`` keyed by the scene and perception
configs and the object, seed and sensor model, so planner changes are re-measured in seconds.
BLAS and K-means run on one thread (the planner's timing target is for one core).

    .venv/bin/python bench/eval_planner_ycb.py [--seeds 0 1 2] [--objects mug banana] [-v]
    .venv/bin/python bench/eval_planner_ycb.py --objects all --per-object  # the 54 of HSQ_YCB_DIR

``--objects`` takes names, or ``paper`` (the paper's 15, ``hsqbench.experiment.config.YCB_OBJECTS``,
the default), ``unseen`` (every other object of objects.csv) or ``all``. ``--per-object`` ends
with one line per object (top grasps ok over its seeds, runs with grasps, failure names) and
the totals over the paper's 15 and the others; ``--json PATH`` writes every run.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
os.environ.setdefault("MUJOCO_GL", "egl")
os.environ.setdefault("PYOPENGL_PLATFORM", "egl")

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import hashlib  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hsqbench.config import to_dict  # noqa: E402
from hsqbench.planner.api import PlanningContext  # noqa: E402
from hsqbench.planner.gripper import GripperModel, resolve_gripper  # noqa: E402
from hsqbench.planner.hsq.config import resolve_config  # noqa: E402
from hsqbench.planner.registry import get_planner  # noqa: E402
from hsqbench.settings import cache_dir  # noqa: E402

#: Spacing of the ground-truth mesh samples, metres (the fused cloud's 2 mm voxel).
GT_SPACING_M = 0.002
#: Part of the cache key: bump when the cached content changes.
CACHE_VERSION = 3


def mesh_samples(model, data, body_id: int, rng: np.random.Generator):
    """World points on the visual meshes of a body, about one per GT_SPACING_M^2 of area, and
    their unit normals (the triangles' winding: outward for the YCB meshes)."""
    import mujoco

    from hsqbench.sim.objects import VISUAL_GROUP

    points, normals = [], []
    for g in np.flatnonzero(model.geom_bodyid == body_id):
        if model.geom_group[g] != VISUAL_GROUP or model.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH:
            continue
        m = model.geom_dataid[g]
        v0, nv = model.mesh_vertadr[m], model.mesh_vertnum[m]
        f0, nf = model.mesh_faceadr[m], model.mesh_facenum[m]
        verts = model.mesh_vert[v0 : v0 + nv].astype(float)
        tri = verts[model.mesh_face[f0 : f0 + nf]]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = 0.5 * np.linalg.norm(cross, axis=1)
        n = int(np.ceil(area.sum() / GT_SPACING_M**2))
        pick = rng.choice(nf, size=n, p=area / area.sum())
        a, b = rng.random((2, n))
        swap = a + b > 1
        a[swap], b[swap] = 1 - a[swap], 1 - b[swap]
        t = tri[pick]
        local = t[:, 0] + a[:, None] * (t[:, 1] - t[:, 0]) + b[:, None] * (t[:, 2] - t[:, 0])
        rot = data.geom_xmat[g].reshape(3, 3)
        points.append(data.geom_xpos[g] + local @ rot.T)
        unit = cross[pick] / np.maximum(2.0 * area[pick], 1e-18)[:, None]
        normals.append(unit @ rot.T)
    return np.concatenate(points), np.concatenate(normals)


def observe(
    name: str, seed: int, sensor: str | None, refresh: bool, scene: str | None = None
) -> dict[str, np.ndarray]:
    """Cloud, table plane and ground-truth mesh samples of one isolated scene (cached).

    ``scene``: a scene config name or YAML path (default ``configs/scene.yaml``)."""
    from hsqbench.sim.perception import Perception, load_perception_config
    from hsqbench.sim.scene import build_scene, load_scene_config

    pcfg = load_perception_config()
    if sensor is not None:
        pcfg = dataclasses.replace(pcfg, sensor_model=sensor)
    scfg = load_scene_config("scene" if scene is None else scene)
    key = json.dumps([CACHE_VERSION, to_dict(scfg), to_dict(pcfg), name, seed], sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:16]
    path = cache_dir() / "eval_planner_ycb" / f"{name}_s{seed}_{pcfg.sensor_model}_{digest}.npz"
    if path.exists() and not refresh:
        with np.load(path) as f:
            return dict(f)
    model, data, info = build_scene("isolated", [name], seed=seed, scene_config=scfg)
    rng = np.random.default_rng(seed)
    with Perception.from_scene(model, info, rng=rng, config=pcfg) as perception:
        obs = perception.observe(data, rng)
    truth, normals = mesh_samples(
        model, data, info.object_body_ids[name], np.random.default_rng(seed)
    )
    out = {
        "points": obs.points,
        "camera_index": obs.camera_index,
        "support_plane": np.asarray(info.support_plane, float),
        "truth": truth,
        "truth_normals": normals,
        "camera_positions": obs.camera_positions,
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, **out)
    return out


def _depth(points: np.ndarray, box: np.ndarray) -> float:
    """Largest distance from a point inside ``box`` ([lower, upper]) to the box's boundary."""
    return float(np.max(np.min(np.minimum(points - box[0], box[1] - points), axis=1)))


def check_grasp(grasp, truth: np.ndarray, plane: np.ndarray, gripper: GripperModel) -> str:
    """'ok' or the names of the failed ground-truth checks (module docstring)."""
    local = (truth - grasp.position) @ grasp.rotation
    opening = grasp.approach_width if np.isfinite(grasp.approach_width) else grasp.width
    boxes = gripper.boxes(opening)
    inside = [np.all((local >= b[0]) & (local <= b[1]), axis=1) for b in boxes]
    between = (
        (np.abs(local[:, 0]) < 0.5 * opening)
        & (np.abs(local[:, 1]) <= 0.5 * gripper.finger_width_m)
        & (local[:, 2] >= -gripper.jaw_length_m)
        & (local[:, 2] <= gripper.fingertip_overhang_m)
    )
    fails = []
    if not between.any():
        fails.append("empty")
    elif np.ptp(local[between, 0]) >= gripper.max_opening_m:
        fails.append("wide")
    for name, hit, box in (
        ("fingers", inside[0] | inside[1], None),
        ("palm", inside[2], boxes[2]),
    ):
        if hit.any():
            # Penetration: how deep the deepest mesh sample lies inside its box, millimetres.
            if box is None:
                depth = max(_depth(local[inside[k]], boxes[k]) for k in (0, 1) if inside[k].any())
            else:
                depth = _depth(local[hit], box)
            fails.append(f"{name}({depth * 1000:.1f}mm)")
    corners = np.array(
        [[b[i, 0], b[j, 1], b[k, 2]] for b in boxes for i in (0, 1) for j in (0, 1) for k in (0, 1)]
    )
    world = grasp.position + corners @ grasp.rotation.T
    if np.min(world @ plane[:3] + plane[3]) < 0.0:
        fails.append("table")
    return "ok" if not fails else "+".join(fails)


def object_names(choice: list[str] | None) -> list[str]:
    """Names for ``--objects``: ``paper``, ``unseen``, ``all`` or the names themselves."""
    from hsqbench.assets.library import ycb_names
    from hsqbench.experiment.config import YCB_OBJECTS

    paper = list(YCB_OBJECTS)
    if not choice or choice == ["paper"]:
        return paper
    if choice == ["all"]:
        return ycb_names()
    if choice == ["unseen"]:
        return [n for n in ycb_names() if n not in paper]
    return choice


def per_object_report(rows: list[tuple], names: list[str]) -> None:
    """One line per object, then the totals over the paper's 15 and the others."""
    from hsqbench.experiment.config import YCB_OBJECTS

    paper = set(YCB_OBJECTS)
    totals: dict[str, list[int]] = {"paper": [0, 0, 0], "others": [0, 0, 0]}
    for name in names:
        mine = [r for r in rows if r[0] == name]
        ok = sum(r[4] == "ok" for r in mine)
        with_grasps = sum(r[2] > 0 for r in mine)
        fails = ",".join(sorted({r[4] for r in mine if r[4] != "ok"}))
        print(f"OBJECT {name:22s} ok {ok}/{len(mine)} grasps {with_grasps}/{len(mine)} {fails}")
        group = totals["paper" if name in paper else "others"]
        group[0] += ok
        group[1] += with_grasps
        group[2] += len(mine)
    for group, (ok, with_grasps, n) in totals.items():
        if n:
            print(
                f"TOTAL {group:7s} top grasp ok {ok}/{n} ({100 * ok / n:.1f} %), runs with "
                f"grasps {with_grasps}/{n}"
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--objects", nargs="*", default=None, help="names, or paper (default), unseen, all"
    )
    parser.add_argument("--seeds", nargs="*", type=int, default=[0, 1, 2])
    parser.add_argument("--sensor", default=None, help="override perception.yaml sensor_model")
    parser.add_argument("--config", default=None, help="planner config name or path")
    parser.add_argument(
        "--planner",
        default="hsq",
        help="a registered planner: hsq, hsq-paper, hsq-no-<addition>, antipodal, single-sq",
    )
    parser.add_argument("--scene", default=None, help="scene config name or path (cameras)")
    parser.add_argument("--refresh", action="store_true", help="re-render cached clouds")
    parser.add_argument("-v", "--verbose", action="store_true", help="candidates after each rule")
    parser.add_argument("--per-object", action="store_true", help="a summary line per object")
    parser.add_argument("--json", default=None, help="write every run to this JSON file")
    args = parser.parse_args()

    names = object_names(args.objects)
    gripper = resolve_gripper(resolve_config(args.config).grasp.gripper)
    planner = get_planner(args.planner, args.config)
    rows = []
    for name in names:
        for seed in args.seeds:
            obs = observe(name, seed, args.sensor, args.refresh, args.scene)
            plane = obs["support_plane"]
            context = PlanningContext(
                support_plane=tuple(plane), seed=seed, camera_positions=obs["camera_positions"]
            )
            if not rows:  # warm-up: imports and config parsing stay out of the first time
                planner.plan(obs["points"][:500], PlanningContext(support_plane=tuple(plane)))
            start = time.process_time()
            res = planner.plan(obs["points"], context)
            cpu = time.process_time() - start
            best = res.best
            if best is not None:
                check = check_grasp(best, obs["truth"], plane, gripper)
                appr = np.round(best.approach_axis, 2)
                tail = (
                    f"top={best.score:.3f} w={best.width:.3f} appr={appr} {best.family} gt={check}"
                )
            else:
                check = "none"
                tail = f"reason: {res.reason}"
            n_pts = len(obs["points"])
            print(
                f"{name:22s} s{seed} pts={n_pts:5d} hsq={len(res.hidden_superquadrics):2d} "
                f"grasps={len(res.grasps):5d} cpu={cpu:.2f}s {tail}",
                flush=True,
            )
            if args.verbose:
                print(f"{'':26s}remaining={res.remaining}", flush=True)
            rows.append((name, seed, len(res.grasps), cpu, check))

    if args.per_object:
        per_object_report(rows, names)
    if args.json:
        keys = ("object", "seed", "n_grasps", "cpu_s", "check")
        out = Path(args.json)
        tmp = out.with_suffix(out.suffix + ".tmp")
        tmp.write_text(json.dumps([dict(zip(keys, r, strict=True)) for r in rows], indent=1))
        tmp.replace(out)

    objects_with = {n for n, _, k, _, _ in rows if k > 0}
    runs_with = sum(k > 0 for _, _, k, _, _ in rows)
    runs_ok = sum(c == "ok" for *_, c in rows)
    cpus = np.array([r[3] for r in rows])
    print(
        f"SUMMARY objects with >=1 grasp at every seed: "
        f"{sum(all(k > 0 for n2, _, k, _, _ in rows if n2 == n) for n in names)}/{len(names)}; "
        f"with >=1 grasp at some seed: {len(objects_with)}/{len(names)}; "
        f"runs with grasps: {runs_with}/{len(rows)}; top grasp ok (ground truth): "
        f"{runs_ok}/{len(rows)}; cpu median {np.median(cpus):.2f}s max {cpus.max():.2f}s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
