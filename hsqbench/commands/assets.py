"""``hsqbench assets``: list, build, download and import the objects of the library."""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import add_jobs, add_protocol, register_output

HELP = "list, build, download (YCB, CC BY 4.0) or import the objects of the library"

_EPILOG = """\
Sources: YCB objects from HSQ_YCB_DIR (<name>/textured.obj + objects.csv), built-in procedural
shapes (proc_*), and meshes registered with `assets import`. Built assets are cached in
HSQ_CACHE_DIR (default assets/build/) by a hash of the mesh files and build parameters.

The YCB Object and Model Set (Calli et al., IEEE RAM 2015) is licensed CC BY 4.0: keep the
ATTRIBUTION.md written by `assets download` with the meshes, and credit YCB in results.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    _add_assets_config(parser, "assets")
    sub = parser.add_subparsers(dest="assets_command", metavar="ACTION", required=True)

    p = sub.add_parser(
        "list", help="show each object: source, mass, size, hull count, built or not"
    )
    _add_assets_config(p)
    p.add_argument("--source", choices=["ycb", "procedural", "imported"], help="only this source")
    _add_build(sub)
    _add_download(sub)
    _add_import(sub)


def _add_assets_config(parser: argparse.ArgumentParser, default: str | None = None) -> None:
    """``--assets-config NAME``, before the action or after it (each action takes it too; its
    default there is left unset so that one given before the action stands)."""
    parser.add_argument(
        "--assets-config",
        default=argparse.SUPPRESS if default is None else default,
        metavar="NAME",
        help="the object library's config: a name in configs/ or a YAML path (default: assets)",
    )
    # Neither spelling after the action may reset a value given before it.
    unset = argparse.SUPPRESS if default is None else None
    deprecated(parser, "--config", "--assets-config", "assets_config", default=unset)


def _add_build(sub: argparse._SubParsersAction) -> None:
    """``assets build``: which objects to build into the cache."""
    p = sub.add_parser(
        "build",
        help="build objects (convex decomposition, inertia, MuJoCo meshes): NAME..., "
        "--protocol NAME, --source SOURCE or --all",
        description="Build objects once into the cache (HSQ_CACHE_DIR). Say which: names, the "
        "objects of a benchmark protocol (--protocol paper), one source (--source procedural) "
        "or the whole library (--all; minutes of CoACD per new YCB object). `hsqbench "
        "benchmark` builds the objects of its protocol itself, so this is never required.",
    )
    _add_assets_config(p)
    p.add_argument("names", nargs="*", metavar="NAME", help="objects to build")
    add_protocol(
        p, None, "the objects a benchmark protocol uses (paper, quick, ... or a YAML path)"
    )
    p.add_argument("--source", choices=["ycb", "procedural", "imported"], help="every object of it")
    p.add_argument("--all", action="store_true", help="every object of the library")
    add_jobs(p, "objects built at once", "assets config's jobs")


def _add_download(sub: argparse._SubParsersAction) -> None:
    """``assets download``: which YCB scans to fetch, and where."""
    p = sub.add_parser(
        "download",
        help="fetch Google 16k YCB scans (CC BY 4.0): NAME..., --protocol NAME or --all",
        description="Fetch the Google 16k YCB scans from the official YCB source (or HSQ_YCB_URL) "
        "into the download folder (HSQ_DATA_DIR/ycb, default assets/ycb), which hsqbench reads "
        "when HSQ_YCB_DIR is unset; or into --dest DIR, laid out for HSQ_YCB_DIR. Commands that "
        "need missing objects download them by themselves, so this is never required. The "
        "models are CC BY 4.0: ATTRIBUTION.md beside them credits them.",
    )
    _add_assets_config(p)
    p.add_argument("names", nargs="*", metavar="NAME", help="YCB objects")
    add_protocol(p, None, "the YCB objects a protocol uses")
    p.add_argument(
        "--all", action="store_true", help="every object of download.objects in the config"
    )
    p.add_argument(
        "--dest",
        type=Path,
        default=None,
        metavar="DIR",
        help="folder to write, then export HSQ_YCB_DIR=DEST (default: the download folder)",
    )
    register_output(p, "dest", "--dest", folder=True)
    p.add_argument(
        "--base-url",
        default=None,
        metavar="URL",
        help="archive server (default: download.base_url in the config)",
    )
    p.add_argument("--force", action="store_true", help="download again objects already present")
    p.add_argument(
        "--keep-archives", action="store_true", help="keep the .tgz files in DEST/.download"
    )


def _add_import(sub: argparse._SubParsersAction) -> None:
    """``assets import``: a folder of meshes and how to read them."""
    p = sub.add_parser("import", help="register (and build) a folder of meshes (obj/stl/ply)")
    _add_assets_config(p)
    p.add_argument(
        "folder",
        type=Path,
        metavar="DIR",
        help="a folder of .obj, .stl or .ply meshes (searched recursively), one object each",
    )
    p.add_argument(
        "--density",
        type=float,
        default=None,
        metavar="KG_M3",
        help="kg/m^3 (default: importer.density_kg_m3)",
    )
    p.add_argument(
        "--scale",
        type=float,
        default=1.0,
        metavar="FACTOR",
        help="multiplies coordinates to get metres (0.001 for mm)",
    )
    p.add_argument(
        "--up",
        choices=["z", "y", "x", "stable"],
        default="z",
        help="file axis that points up; 'stable': most probable resting pose (default: z)",
    )
    p.add_argument("--prefix", default="", metavar="TEXT", help="prepended to every object name")
    p.add_argument("--no-build", action="store_true", help="only register the meshes")
    add_jobs(p, "objects built at once", "assets config's jobs")


def run(args: argparse.Namespace) -> int:
    from hsqbench.assets.config import load_assets_config

    config = load_assets_config(args.assets_config or "assets")
    action = args.assets_command
    if action == "list":
        return _list(config, args.source)
    if action == "build":
        return _build(config, _build_selection(config, args), args.jobs)
    if action == "download":
        return _download(config, args)
    return _import(config, args)


def _list(config, source: str | None) -> int:
    from hsqbench.assets.build import load_cached
    from hsqbench.assets.library import object_names, object_spec
    from hsqbench.settings import cache_dir

    names = object_names(source, config)
    rows = [("name", "source", "mass_kg", "size_mm (x y z)", "hulls", "built")]
    for name in names:
        spec = object_spec(name, config)
        asset = load_cached(spec, config, cache_dir())
        mass = asset.mass_kg if asset else spec.mass_kg
        rows.append(
            (
                name,
                spec.source,
                "-" if mass is None else f"{mass:.3f}",
                "-" if asset is None else " ".join(f"{1000 * e:.0f}" for e in asset.extents),
                "-" if asset is None else str(len(asset.collision_meshes)),
                "yes" if asset else "no",
            )
        )
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip())
    built = sum(r[-1] == "yes" for r in rows[1:])
    print(f"{len(names)} objects, {built} built (cache: {cache_dir()})")
    if source in (None, "ycb"):
        from hsqbench.assets.on_demand import missing_ycb
        from hsqbench.settings import default_ycb_dir, shown_path

        missing = missing_ycb([o.name for o in config.download.objects], config)
        if missing:
            print(
                f"{len(missing)} more YCB objects are downloaded into "
                f"{shown_path(default_ycb_dir())} when a command needs them (HSQ_YCB_DIR is "
                "not set), or now with `hsqbench assets download`"
            )
    return 0


def _library(source: str | None, config) -> list[str]:
    """Every object of ``source`` (default: all), YCB ones not downloaded yet included (they
    are fetched before the build)."""
    from hsqbench.assets.library import object_names, ycb_names

    ycb = ycb_names() if source in (None, "ycb") else []
    others = [] if source == "ycb" else object_names(source, config)
    return list(dict.fromkeys(ycb + others))


def _build_selection(config, args: argparse.Namespace) -> list[str]:
    """The objects ``assets build`` was asked for: exactly one way of saying which."""
    from hsqbench.cli import CommandError

    ways = [bool(args.names), args.protocol is not None, args.all]
    if sum(ways) > 1:
        raise CommandError("give object names, --protocol or --all, not several of them")
    if args.names:
        return list(args.names)
    if args.protocol is not None:
        from hsqbench.experiment.config import load_experiment_config

        return list(load_experiment_config(args.protocol).object_names())
    if args.all or args.source:
        return _library(args.source, config)
    n = len(_library(None, config))
    raise CommandError(
        "say which objects to build: names (`hsqbench assets build mug bowl`), the objects of "
        f"a protocol (`--protocol paper`), one source (`--source procedural`), or all {n} "
        "objects of the library (`--all`); `hsqbench assets list` shows them. `hsqbench "
        "benchmark` builds what its protocol needs by itself."
    )


def _build(config, names: list[str], jobs: int | None) -> int:
    import warnings

    from hsqbench.assets.library import failure_message, prepare_objects
    from hsqbench.assets.on_demand import fetch_missing

    if not names:
        print("no objects to build")
        return 0
    start = time.perf_counter()
    fetch_missing(names, config)
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        report = prepare_objects(names, jobs=jobs, config=config)
    for a in report.assets.values():
        info = a.info
        note = (
            "" if info.get("collision_method", "coacd") == "coacd" else "  (convex-hull fallback)"
        )
        print(
            f"{a.name:24s} {a.source:10s} {a.mass_kg:7.3f} kg  {len(a.collision_meshes):3d} hulls  "
            f"inertia from {info.get('inertia_method', '?'):11s} built in {info.get('build_s', 0):6.1f} s{note}"
        )
    print(f"{len(report.assets)} objects ready in {time.perf_counter() - start:.1f} s")
    if report.failed:
        print(failure_message(report.failed), file=sys.stderr)
        return 1
    return 0


def _download(config, args: argparse.Namespace) -> int:
    from hsqbench.assets.download import download_ycb
    from hsqbench.cli import CommandError
    from hsqbench.settings import default_ycb_dir, shown_path, ycb_base_url, ycb_dir_is_set

    table = [o.name for o in config.download.objects]
    if sum([bool(args.names), args.protocol is not None, args.all]) != 1:
        raise CommandError(
            "say which YCB objects to download: names (`hsqbench assets download mug bowl`), "
            f"those of a protocol (`--protocol paper`), or all {len(table)} (`--all`)"
        )
    names = list(args.names) if args.names else table
    if args.protocol is not None:
        from hsqbench.experiment.config import load_experiment_config

        used = load_experiment_config(args.protocol).object_names()
        names = [n for n in used if n in table]
    dest = args.dest if args.dest is not None else default_ycb_dir()
    report = download_ycb(
        dest,
        config.download,
        names=names,
        base_url=args.base_url or ycb_base_url(),
        force=args.force,
        keep_archives=args.keep_archives,
    )
    print(
        f"downloaded {len(report.downloaded)}, already present {len(report.skipped)}, "
        f"failed {len(report.failed)} (in {shown_path(dest)})"
    )
    for name, why in report.failed.items():
        print(f"  {name}: {why}")
    if report.failed:
        from hsqbench.cli import CommandError

        raise CommandError(
            f"{len(report.failed)} object(s) failed; run the same command again to retry"
        )
    if args.dest is not None:
        print(f"now: export HSQ_YCB_DIR={os.path.abspath(args.dest)}")
    elif ycb_dir_is_set():
        print("note: HSQ_YCB_DIR is set, so hsqbench reads that folder, not this one")
    return 0


def _import(config, args: argparse.Namespace) -> int:
    from hsqbench.assets.importer import register
    from hsqbench.assets.library import object_names
    from hsqbench.settings import cache_dir

    density = args.density if args.density is not None else config.importer.density_kg_m3
    if not density > 0:
        raise ValueError(f"--density must be > 0 kg/m^3, got {density}")
    reserved = set(object_names("ycb", config)) | set(object_names("procedural", config))
    reserved |= {o.name for o in config.download.objects}
    specs = register(
        args.folder,
        cache_dir(),
        reserved,
        density_kg_m3=density,
        scale=args.scale,
        up=args.up,
        prefix=args.prefix,
        rgba=config.importer.rgba,
    )
    print(f"registered {len(specs)} object(s): {', '.join(s.name for s in specs)}")
    if args.no_build:
        return 0
    return _build(config, [s.name for s in specs], args.jobs)
