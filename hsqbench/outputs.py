"""Where a command or API call will write, checked before any work starts: a trial that runs
for minutes must not lose its result to a path that could never be written.

Every command's output options (``--json``, ``--png``, ``--csv``, ``--mjcf``, ``--rerun``,
``--run``, ``--dest``: registered by :mod:`hsqbench.commands._options`) pass through
:func:`check_output` once the command line is read; the runner checks its run folder so the
Python API does too. Nothing is created here: a bad path leaves nothing behind.
"""

from __future__ import annotations

import os
from pathlib import Path


class OutputPathError(ValueError):
    """An output path that cannot be written as asked (one line: the problem and the fix)."""


def _nearest_existing(path: Path) -> Path:
    for p in (path, *path.parents):
        if p.exists():
            return p
    return Path(".")


def check_output(
    path: str | Path, *, folder: bool, option: str, example: str = "", suffix: str = ""
) -> Path:
    """``path`` if a file (``folder`` False) or a folder can be written there, else raises.

    ``option`` names what the user gave (``--json``); ``example``, a file name to suggest when
    a folder was given for a file (``trial.json``); ``suffix``, the extension the file's writer
    needs (``.png``: the image writer picks the format by it).

    Raises:
        OutputPathError: the path is a folder where a file is wanted or the other way round,
            lies under a file, or under a folder this process cannot write.
    """
    path = Path(path)
    shown = f"{option} {path}"
    if path.is_dir() and not folder:
        name = example or "out" + (path.suffix or "")
        raise OutputPathError(f"{shown}: is a folder; give a file path, e.g. {path / name}")
    if path.exists() and not path.is_dir() and folder:
        raise OutputPathError(f"{shown}: is a file, not a folder; give a folder path")
    if suffix and not folder and path.suffix.lower() != suffix:
        raise OutputPathError(
            f"{shown}: the file needs the {suffix} extension, e.g. {path.with_suffix(suffix)}"
        )
    base = _nearest_existing(path)
    if base != path and not base.is_dir():
        raise OutputPathError(f"{shown}: {base} is a file, so nothing can be written under it")
    if not os.access(base, os.W_OK):
        whose = "the file" if base == path and not folder else "the folder"
        raise OutputPathError(f"{shown}: {whose} {base} is not writable by this user")
    return path
