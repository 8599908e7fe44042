"""``hsqbench plan``: grasps for a point cloud file, printed as a table and written as JSON."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import (
    PLANNER_SPEC_HELP,
    add_output,
    add_planner,
    add_scene,
    add_seed,
)

HELP = "plan grasps on a point cloud (.ply, .pcd, .npy, .xyz) and print the best ones"

_EPILOG = """\
The cloud is in metres, in any frame; --support-plane gives the table in that frame as
a b c d with a x + b y + c z + d = 0 and (a, b, c) the normal toward the free side
(e.g. 0 0 1 0 for a table at z = 0). --camera X Y Z (once per camera, same frame) gives the
cameras' centres: contacts none of them sees then need no support, and the hand is kept out of
the hidden superquadrics where no camera saw free space (rule 6).
Grasp frame: P_G is the closing point (between the pads), 'closing' the axis joining the pads,
'approach' the direction from the palm toward P_G.

A cloud in other units (millimetres) is refused with the --scale that makes it metres.

Exit status: 0 when grasps were found, 1 when none survived (the reason is printed),
2 on bad input (unreadable, empty or non-finite cloud, a size no cloud in metres has, bad option) and when the planner
raised or broke its contract (one line names its file and line).
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("cloud", type=Path, metavar="CLOUD", help="point cloud file, metres")
    add_scene(
        parser,
        "isolated",
        "the scene the cloud shows: one object, or several (packed, pile: the centroid term is "
        "left out)",
    )
    deprecated(parser, "--packed", "--scene packed", "scene", flag="packed")
    parser.add_argument(
        "--top", type=int, default=10, metavar="K", help="grasps to print and write (0: all)"
    )
    add_output(parser, "json", "write the result as JSON here")
    parser.add_argument(
        "--planner-config",
        default=None,
        metavar="NAME",
        help="the planner's config: a name in configs/ or a YAML path (default: its own)",
    )
    deprecated(parser, "--config", "--planner-config", "planner_config")
    add_seed(parser, "planner seed", default=None)
    parser.add_argument(
        "--support-plane",
        type=float,
        nargs=4,
        metavar=("A", "B", "C", "D"),
        help="table plane a x + b y + c z + d = 0, normal toward the free side",
    )
    parser.add_argument(
        "--camera",
        type=float,
        nargs=3,
        action="append",
        metavar=("X", "Y", "Z"),
        help="a camera centre in the cloud's frame, metres (repeat for each camera)",
    )
    add_planner(parser, f"{PLANNER_SPEC_HELP} (default: hsq)", default="hsq")
    parser.add_argument(
        "--scale",
        type=float,
        default=1.0,
        metavar="FACTOR",
        help="multiplies the cloud's coordinates to get metres (0.001 for mm; --camera and "
        "--support-plane stay in metres)",
    )


def _table(result, top: int) -> str:
    grasps = result.grasps if top <= 0 else result.grasps[:top]
    header = (
        f"{'rank':>4} {'score':>6} {'width':>7}  {'P_G [m]':^24}  {'closing':^20}  "
        f"{'approach':^20}  {'factors a/b/g/d':^23} {'sq':>3} family"
    )
    rows = [header]
    for rank, g in enumerate(grasps):
        factors = "/".join(
            f"{g.factors[k]:.2f}" if k in g.factors else "  - "
            for k in ("h_alpha", "h_beta", "h_gamma", "h_delta")
        )
        rows.append(
            f"{rank:>4} {g.score:6.3f} {1000 * g.width:5.1f}mm  "
            f"{_vec(g.position, 3)}  {_vec(g.closing_axis, 2)}  {_vec(g.approach_axis, 2)}  "
            f"{factors:^23} {g.source:>3} {g.family}"
        )
    return "\n".join(rows)


#: Largest extent of a cloud in metres: over twice the range of any depth camera near a table
#: (a Kinect sees 4.5 m), so a larger cloud is in other units (a can in millimetres spans 100).
MAX_CLOUD_EXTENT_M = 10.0


def _check_units(path: Path, points, scale: float) -> None:
    """The cloud is in metres at ``scale`` (the check ``assets import`` makes of a mesh)."""
    from hsqbench.assets.importer import MIN_EXTENT_M
    from hsqbench.units import check_metres

    if not scale > 0:
        raise ValueError(f"--scale must be > 0 (metres per cloud unit), got {scale:g}")
    extent = float((points.max(axis=0) - points.min(axis=0)).max())
    if extent == 0.0:  # no scale makes one place an object
        raise ValueError(f"{path}: all its {len(points)} point(s) are at one place")
    check_metres(
        str(path),
        extent,
        scale,
        min_m=MIN_EXTENT_M,
        max_m=MAX_CLOUD_EXTENT_M,
        small=f"under the {MIN_EXTENT_M * 1000:g} mm the cameras can see",
        large=f"over the {MAX_CLOUD_EXTENT_M:g} m a depth camera's cloud spans",
    )


def _vec(v, digits: int) -> str:
    return "(" + ", ".join(f"{x:+.{digits}f}" for x in v) + ")"


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from hsqbench.cloud_io import read_cloud
    from hsqbench.planner.api import PlanningContext
    from hsqbench.planner.failure import checked_plan
    from hsqbench.planner.registry import get_planner
    from hsqbench.settings import code_version

    points = read_cloud(args.cloud)
    _check_units(args.cloud, points, args.scale)
    if args.scale != 1.0:
        points = points * args.scale
    planner = get_planner(args.planner, args.planner_config)
    context = PlanningContext(
        support_plane=tuple(args.support_plane) if args.support_plane else None,
        packed=args.scene != "isolated",
        seed=args.seed,
        camera_positions=None if args.camera is None else np.asarray(args.camera, dtype=float),
    )
    result = checked_plan(planner, points, context)  # PlannerError: one line, exit 2
    print(f"{args.cloud}: {points.shape[0]} points, planner {args.planner}")
    if result.remaining:
        steps = " -> ".join(f"{k} {v}" for k, v in result.remaining.items())
        print(f"candidates: {steps}")
    if result.timings:
        print("time: " + ", ".join(f"{k} {v:.3f} s" for k, v in result.timings.items()))
    if result.grasps:
        shown = len(result.grasps) if args.top <= 0 else min(args.top, len(result.grasps))
        print(f"{len(result.grasps)} grasps; best {shown}:")
        print(_table(result, args.top))
    else:
        print(f"no grasp: {result.reason}")
    if args.json:
        out = result.to_dict(top=None if args.top <= 0 else args.top)
        out["input"] = {
            "cloud": str(args.cloud),
            "n_points": int(points.shape[0]),
            "config": args.planner_config,
            "seed": args.seed,
            "scale": args.scale,
            "scene": args.scene,
            "packed": args.scene != "isolated",
            "support_plane": context.support_plane,
            "camera_positions": args.camera,
            "code_version": code_version(),
        }
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")
    return 0 if result.grasps else 1
