"""``hsqbench scene``: build a benchmark scene, list what it holds, save a picture of it."""

from __future__ import annotations

import argparse
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import SCENES, add_output, add_scene, add_seed
from hsqbench.names import check_objects

HELP = "build an isolated, packed or pile scene, print what it holds, render it to a PNG or export it as MJCF"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_scene(
        parser,
        "packed",
        "packed: objects standing apart; pile: dropped into a box, the box removed",
    )
    deprecated(parser, "--kind", "--scene", "scene", choices=SCENES)
    add_seed(parser, "the same seed gives the same scene (default 0)")
    parser.add_argument(
        "--objects",
        nargs="+",
        default=None,
        metavar="NAME",
        help="object names (default: drawn by seed from the 15 YCB objects)",
    )
    add_output(parser, "png", "write a picture here")
    add_output(
        parser,
        "mjcf",
        "write the scene as self-contained MJCF: DIR/scene.xml (settled state as keyframe "
        "'initial') and DIR/assets/; open with `python -m mujoco.viewer --mjcf DIR/scene.xml`",
        folder=True,
        dest="xml",
    )
    deprecated(parser, "--xml", "--mjcf", "xml", type=Path)
    parser.add_argument(
        "--png-camera",
        dest="camera",
        default=None,
        metavar="NAME",
        help="the camera --png renders from (default: the viewer camera; cam_left/cam_right "
        "show the depth views)",
    )
    deprecated(parser, "--camera", "--png-camera", "camera")


def render_png(model, data, camera: str, path: Path) -> None:
    """Render ``camera`` offscreen (MUJOCO_GL=egl on headless machines) and save a PNG."""
    import mujoco
    from PIL import Image

    try:
        cam_id = model.camera(camera).id
    except KeyError as exc:
        names = [model.camera(i).name for i in range(model.ncam)]
        raise ValueError(f"no camera {camera!r}; cameras: {names}") from exc
    width, height = (int(v) for v in model.cam_resolution[cam_id])
    with mujoco.Renderer(model, height=height, width=width) as renderer:
        renderer.update_scene(data, camera=cam_id)
        image = renderer.render()
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(image).save(path)


def run(args: argparse.Namespace) -> int:
    from hsqbench.assets.on_demand import fetch_missing
    from hsqbench.sim.scene import build_scene_spec

    if args.objects:
        check_objects(args.objects)
        fetch_missing(args.objects)  # YCB objects not downloaded yet (only without HSQ_YCB_DIR)
    spec, model, data, info = build_scene_spec(args.scene, args.objects, seed=args.seed)
    print(f"{info.kind} scene, seed {info.seed}: {', '.join(info.objects)}")
    for name in info.objects:
        x, y, z = info.initial_poses[name][:3]
        print(f"  {name:22s} at ({x:+.3f}, {y:+.3f}, {z:+.3f}) m")
    for i, why in enumerate(info.rejected_drops):
        print(f"  drop {i + 1} rejected and redrawn: {why}")
    print(
        f"settled in {info.settle_time_s:.2f} s simulated (max speed {info.max_speed_after_settle:.4f}); "
        f"built in {info.build_time_s:.1f} s"
    )
    if args.png is not None:
        camera = args.camera or info.viewer_camera
        render_png(model, data, camera, args.png)
        print(f"wrote {args.png} ({camera})")
    if args.xml is not None:
        from hsqbench.sim.scene_export import export_scene

        path = export_scene(spec, model, info, args.xml)
        print(f"wrote {path}; open it with: python -m mujoco.viewer --mjcf {path}")
    return 0
