"""``hsqbench view OUT.rrd``: open a recorded episode in the Rerun viewer, or say how to."""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
from pathlib import Path

HELP = "open a recorded episode (.rrd from --rerun) in the Rerun viewer"

_EPILOG = """\
Record an episode with `hsqbench trial --object NAME --seed N --rerun OUT.rrd`.

The native viewer needs a display (DISPLAY or WAYLAND_DISPLAY on Linux) and the `rerun`
executable of the rerun-sdk package. Without them this prints a summary of the recording and how
to open it elsewhere; --web serves it to a browser from this machine instead.

Exit status: 0 when the file is a readable recording (viewer started, or instructions printed),
2 when it is missing or unreadable.
"""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = _EPILOG
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.add_argument("path", type=Path, metavar="OUT.rrd", help="a recording from --rerun")
    parser.add_argument(
        "--web",
        action="store_true",
        help="serve the web viewer over HTTP from here (blocks until Ctrl-C)",
    )
    parser.add_argument(
        "--port", type=int, default=9090, metavar="N", help="HTTP port of --web (default 9090)"
    )


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


def run(args: argparse.Namespace) -> int:
    from hsqbench.viz.rrd import read_recording

    if not 1 <= args.port <= 65535:
        raise ValueError(f"--port must be a TCP port 1-65535, got {args.port}")
    summary = read_recording(args.path)  # FileNotFoundError / ValueError -> exit 2
    for line in _describe(summary):
        print(line)
    exe = viewer_executable()
    pin = f"pip install rerun-sdk=={_sdk_version()}"
    path = str(args.path)
    if args.web:
        if exe is None:
            print(f"the `rerun` executable is not installed here ({pin}); nothing to serve with")
            return 0
        print(
            f"serving {path} at http://localhost:{args.port} (and gRPC on port 9876); from "
            f"another machine: ssh -L {args.port}:localhost:{args.port} -L 9876:localhost:9876 "
            "<this host>, then open the URL Rerun prints. Ctrl-C stops."
        )
        sys.stdout.flush()
        try:
            return subprocess.call([exe, "--web-viewer", "--web-viewer-port", str(args.port), path])
        except KeyboardInterrupt:
            return 0
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
