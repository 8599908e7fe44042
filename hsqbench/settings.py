"""Where hsqbench finds its data: environment settings and repository paths.

Settings (environment variables):

- ``HSQ_YCB_DIR``: your own folder of YCB meshes, laid out as ``<name>/textured.obj`` with
  ``objects.csv``; hsqbench reads it and never writes to it.
- ``HSQ_DATA_DIR``: hsqbench's own data folder (default ``<repo>/assets``). Without
  ``HSQ_YCB_DIR``, the YCB objects a command needs are downloaded into its ``ycb/`` folder.
- ``HSQ_YCB_URL``: a mirror of the YCB archives (default: ``download.base_url`` of
  ``configs/assets.yaml``, the official source).
- ``HSQ_MODELS_DIR``: your own folder of pretrained network weights (``giga/vgn_packed.pt``,
  ...; the ``vgn`` and ``giga`` planners); hsqbench reads it and never writes to it. Without it,
  missing weights are downloaded into the data folder's ``models/``.
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
#: The benchmark protocols users run (``--protocol paper``), apart from the component configs.
PROTOCOL_DIR = CONFIG_DIR / "protocols"
#: The built-in robustness sweeps (``hsqbench sweep depth_noise``).
SWEEP_DIR = PROTOCOL_DIR / "sweeps"
SCENES_DIR = REPO_ROOT / "scenes"
#: Where a run named without a path goes (``--run NAME``, the Makefile's targets): ``runs/``,
#: git-ignored, so no command a user runs changes a tracked file. ``results/`` holds the canonical
#: runs behind the README, written only by ``make results``, which names its folders as paths.
RESULTS_DIR = REPO_ROOT / "runs"


class SettingError(RuntimeError):
    """A required setting is missing or points at something unusable."""


def data_dir() -> Path:
    """hsqbench's own data folder (``HSQ_DATA_DIR``, default ``<repo>/assets``)."""
    return Path(os.environ.get("HSQ_DATA_DIR") or REPO_ROOT / "assets")


def default_ycb_dir() -> Path:
    """Where YCB objects are downloaded when ``HSQ_YCB_DIR`` is unset."""
    return data_dir() / "ycb"


def ycb_dir_is_set() -> bool:
    """Whether the user points hsqbench at their own YCB folder (then nothing is downloaded)."""
    return bool(os.environ.get("HSQ_YCB_DIR"))


def ycb_base_url() -> str | None:
    """``HSQ_YCB_URL``, a mirror of the YCB archives, if set."""
    return os.environ.get("HSQ_YCB_URL") or None


def shown_path(path: Path) -> str:
    """``path`` as a message shows it: relative to the working folder when inside it."""
    path = Path(path).resolve()
    try:
        return str(path.relative_to(Path.cwd().resolve())) or "."
    except ValueError:
        return str(path)


def ycb_dir(required: bool = True) -> Path | None:
    """The YCB source folder: ``HSQ_YCB_DIR``, else the download folder once it holds objects.

    Raises:
        SettingError: when ``required`` and there is none; the message names every way to get
            the meshes.
    """
    value = os.environ.get("HSQ_YCB_DIR")
    if value:
        if Path(value).is_dir():
            return Path(value).resolve()
        if not required:
            return None
        raise SettingError(
            f"HSQ_YCB_DIR={value} is not a folder: point it at a folder of YCB meshes laid out "
            "as <name>/textured.obj with objects.csv, or unset it to let hsqbench download the "
            "objects it needs into its data folder"
        )
    folder = default_ycb_dir()
    if (folder / "objects.csv").is_file():
        return folder.resolve()
    if not required:
        return None
    raise SettingError(
        "no YCB objects yet: HSQ_YCB_DIR is not set and the download folder "
        f"({shown_path(folder)}) is empty. `hsqbench benchmark` downloads the objects its "
        "protocol needs by itself; `hsqbench assets download NAME... | --protocol paper | --all` "
        "fetches them now; or `export HSQ_YCB_DIR=DIR` for your own YCB folder laid out as "
        "<name>/textured.obj with objects.csv."
    )


def models_dir_is_set() -> bool:
    """Whether the user points hsqbench at their own folder of network weights."""
    return bool(os.environ.get("HSQ_MODELS_DIR"))


def models_dir() -> Path:
    """Where pretrained network weights are read: ``HSQ_MODELS_DIR``, else the data folder's
    ``models/`` (where missing weights are downloaded).

    Raises:
        SettingError: ``HSQ_MODELS_DIR`` is set but is not a folder.
    """
    value = os.environ.get("HSQ_MODELS_DIR")
    if not value:
        return data_dir() / "models"
    if not Path(value).is_dir():
        raise SettingError(
            f"HSQ_MODELS_DIR={value} is not a folder: point it at a folder holding giga/*.pt "
            "(see docs/learned-baselines.md), or unset it to download the weights into the "
            "data folder"
        )
    return Path(value).resolve()


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
