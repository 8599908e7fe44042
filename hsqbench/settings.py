"""Where hsqbench finds its data: environment settings and repository paths.

Settings (environment variables):

- ``HSQ_YCB_DIR``: folder of YCB meshes, laid out as ``<name>/textured.obj`` with ``objects.csv``.
- ``MENAGERIE_ROOT``: a local MuJoCo Menagerie checkout; read by the ``mujoco_menagerie`` package.
- ``HSQ_CACHE_DIR``: where built object assets go (default ``<repo>/assets/build``).
- ``MUJOCO_GL``: ``egl`` for offscreen rendering on machines without a display.
"""

from __future__ import annotations

import os
import subprocess
from functools import cache
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
CONFIG_DIR = REPO_ROOT / "configs"
SCENES_DIR = REPO_ROOT / "scenes"
RESULTS_DIR = REPO_ROOT / "results"


class SettingError(RuntimeError):
    """A required setting is missing or points at something unusable."""


def ycb_dir(required: bool = True) -> Path | None:
    """The YCB source folder from ``HSQ_YCB_DIR``.

    Raises:
        SettingError: when ``required`` and the variable is unset or not a folder; the message
            names both ways to get the meshes.
    """
    value = os.environ.get("HSQ_YCB_DIR")
    if value and Path(value).is_dir():
        return Path(value).resolve()
    if not required:
        return None
    why = "HSQ_YCB_DIR is not set" if not value else f"HSQ_YCB_DIR={value} is not a folder"
    raise SettingError(
        f"{why}. Either point it at a folder of YCB meshes laid out as <name>/textured.obj "
        "with objects.csv (for example `export HSQ_YCB_DIR=../shared/ycb`), or fetch them with "
        "`hsqbench assets download --dest DIR` and then `export HSQ_YCB_DIR=DIR`."
    )


def cache_dir() -> Path:
    """Folder for built assets (CoACD hulls, MuJoCo meshes), created on demand."""
    path = Path(os.environ.get("HSQ_CACHE_DIR", REPO_ROOT / "assets" / "build"))
    path.mkdir(parents=True, exist_ok=True)
    return path


@cache
def code_version() -> str:
    """``git describe`` of the checkout (with ``-dirty`` when modified), else the package version."""
    from hsqbench import __version__

    try:
        out = subprocess.run(
            ["git", "describe", "--always", "--dirty", "--abbrev=12"],
            cwd=REPO_ROOT,
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        )
        return out.stdout.strip() or __version__
    except (OSError, subprocess.SubprocessError):
        return __version__
