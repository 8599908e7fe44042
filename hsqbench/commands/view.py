"""``hsqbench view RECORDING``: open a recorded episode in the Rerun viewer, or say how to."""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

from hsqbench.commands._deprecated import deprecated

HELP = "open a recorded episode (.rrd from --rerun) in the Rerun viewer"

#: Default ports of ``--web``: the viewer's page (Rerun's usual one) and the recording's server
#: (next to Rerun's gRPC port 9876, so a running native viewer does not clash with it).
WEB_PORT = 9090
RRD_PORT = 9877

_EPILOG = """\
Record an episode with `hsqbench trial --object NAME --seed N --rerun episode.rrd`.

The native viewer needs a display (DISPLAY or WAYLAND_DISPLAY on Linux) and the `rerun`
executable of the rerun-sdk package. Without them this prints a summary of the recording and how
to open it elsewhere; --web serves it to a browser from this machine instead: it prints the
address that opens the episode (the web viewer's page on --web-port, the recording and its
default layout served as files on --rrd-port) and serves until Ctrl-C. From another machine,
forward both ports (ssh -L) and open the same address. Both servers sleep while idle.

Exit status: 0 when the file is a readable recording (viewer started, or instructions printed),
2 when it is missing or unreadable.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument(
        "path", type=Path, metavar="RECORDING", help="a .rrd recording (from --rerun PATH)"
    )
    parser.add_argument(
        "--web",
        action="store_true",
        help="serve the episode to a browser from here and print its address (until Ctrl-C)",
    )
    parser.add_argument(
        "--web-port",
        type=int,
        default=WEB_PORT,
        metavar="N",
        help=f"HTTP port of the web viewer's page (default {WEB_PORT}; 0: a free one)",
    )
    parser.add_argument(
        "--rrd-port",
        type=int,
        default=RRD_PORT,
        metavar="N",
        help=f"HTTP port that serves the recording to the page (default {RRD_PORT}; 0: a free one)",
    )
    deprecated(parser, "--port", "--web-port", "web_port", type=int)


def has_display(environ: dict[str, str] | None = None, platform: str | None = None) -> bool:
    """Whether a native window can be shown: always on macOS and Windows; on other systems when
    ``DISPLAY`` or ``WAYLAND_DISPLAY`` is set."""
    env = os.environ if environ is None else environ
    plat = sys.platform if platform is None else platform
    if plat == "darwin" or plat.startswith("win"):
        return True
    return bool(env.get("DISPLAY") or env.get("WAYLAND_DISPLAY"))


def viewer_executable() -> str | None:
    """The ``rerun`` executable: next to this Python (a venv's bin/) first, then on PATH."""
    name = "rerun.exe" if sys.platform.startswith("win") else "rerun"
    beside = Path(sys.executable).parent / name
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return shutil.which("rerun")


def _sdk_version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("rerun-sdk")
    except PackageNotFoundError:
        return "?"


def _describe(summary) -> list[str]:
    times = summary.timeline("sim_time")
    span = f"sim_time {times[0]:.2f}-{times[-1]:.2f} s" if times.size else "no sim_time"
    lines = [
        f"{summary.path}: {summary.size_bytes / 1e6:.1f} MB, {len(summary.entity_paths)} entities, "
        f"{span}"
    ]
    outcome = summary.texts.get("outcome")
    if outcome:
        first = next((line for line in outcome.splitlines() if line.strip()), "")
        lines.append(f"last outcome: {first.lstrip('# ').strip()}")
    return lines


def _ports(args: argparse.Namespace) -> tuple[int, int]:
    for name in ("web_port", "rrd_port"):
        port = getattr(args, name)
        if not 0 <= port <= 65535:
            flag = "--" + name.replace("_", "-")
            raise ValueError(f"{flag} must be a TCP port 0-65535 (0: a free one), got {port}")
    if args.web_port and args.web_port == args.rrd_port:
        raise ValueError(f"--web-port and --rrd-port are both {args.web_port}: give two ports")
    return args.web_port, args.rrd_port


def _wait() -> None:
    """Block until Ctrl-C without using the CPU (the servers run in their own threads)."""
    import threading

    threading.Event().wait()


def _serve_web(summary, web_port: int, rrd_port: int) -> int:
    """Serve the recording and its default layout; print the address; wait for Ctrl-C."""
    import tempfile

    from hsqbench.viz.blueprint import episode_blueprint, save_blueprint
    from hsqbench.viz.web import serve_files, serve_viewer, viewer_url

    names = summary.camera_names
    first = summary.camera_positions.get(f"world/cameras/{names[0]}") if names else None
    layout = episode_blueprint(names, first, summary.floor_centre)
    with tempfile.TemporaryDirectory(prefix="hsqbench-view-") as tmp:
        rbl = save_blueprint(layout, Path(tmp) / f"{summary.path.stem}.rbl")
        files = serve_files([summary.path, rbl], rrd_port)
        try:
            port = serve_viewer(web_port)
            print(f"open {viewer_url(port, files.urls)}")
            print(
                f"(from another machine: ssh -L {port}:localhost:{port} -L {files.port}:"
                f"localhost:{files.port} <this host>, then open the same address) Ctrl-C stops.",
                flush=True,
            )
            _wait()
        except KeyboardInterrupt:
            pass
        finally:
            files.close()
    return 0


def run(args: argparse.Namespace) -> int:
    from hsqbench.viz.rrd import read_recording

    web_port, rrd_port = _ports(args)
    summary = read_recording(args.path)  # FileNotFoundError / ValueError -> exit 2
    for line in _describe(summary):
        print(line)
    if args.web:
        return _serve_web(summary, web_port, rrd_port)
    exe = viewer_executable()
    pin = f"pip install rerun-sdk=={_sdk_version()}"
    path = str(args.path)
    if exe is None:
        print(
            f"the Rerun viewer (`rerun`) is not installed; open it elsewhere with `rerun {path}` "
            f"({pin}), or install it here"
        )
        return 0
    if not has_display():
        print(
            f"no display (DISPLAY and WAYLAND_DISPLAY are unset); open it elsewhere with "
            f"`rerun {path}` ({pin}), or serve it to a browser from here with "
            f"`hsqbench view {path} --web`"
        )
        return 0
    subprocess.Popen(
        [exe, path],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    print(f"opened {path} in the Rerun viewer ({exe})")
    return 0
