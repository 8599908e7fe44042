"""The published VGN and GIGA weights: where they are, their checksums, and a strict load.

Files ``giga/{network}_{training}.pt`` (``vgn_packed``, ``vgn_pile``, ``giga_packed``,
``giga_pile``) under the models folder (:func:`hsqbench.settings.models_dir`): the user's
``HSQ_MODELS_DIR``, read only, or else the data folder's ``models/``, where a missing file is
downloaded on first use from ``weights_url`` (``configs/volumetric.yaml``) by the YCB download's
machinery (``.part`` file, resume, size and sha256 checks, atomic rename). Every file is checked
against the sha256 below before torch reads it, and its state dict must match our module key for
key and shape for shape (:func:`load_strict`).

Provenance: ``data/models/`` of github.com/supersglzc/GIGA at commit 30efe59 (2023-08-23), forked
from UT-Austin-RPL/GIGA, whose README ships the same files in its data archive. GIGA's code is MIT,
VGN's BSD-3; the weights carry no licence of their own: credit both papers.
"""

from __future__ import annotations

import functools
import hashlib
import sys
from pathlib import Path
from typing import Any

from hsqbench.settings import models_dir, models_dir_is_set, shown_path

#: sha256 of each published file (the models folder's README lists the same).
SHA256 = {
    "vgn_packed": "c9d8f6d4b1afdab912b3299ddae14a4bc1c7daecb0b6e81a21f70bdcb36d218d",
    "vgn_pile": "c623ea8418d1f853de83ccf26e9faed58b3ab2870ea5e72d6de49466bc17c3a1",
    "giga_packed": "e0f86e3b01dbbde682aa56b3ae605991e58d6d0e0e78380aded6b6c13b3fbc67",
    "giga_pile": "dbca164667336de89f85f08335008fd6d7099af18dc14714d0989ec4bc054fdb",
}
#: Sub-folder of the models folder holding them.
FOLDER = "giga"
#: The smallest file is 1.26 MB; anything much smaller is an error page or an LFS pointer.
MIN_BYTES = 100_000


class WeightsError(RuntimeError):
    """A weight file is missing, cannot be fetched, is corrupt, or does not fit the network."""


def weights_name(network: str, training: str) -> str:
    name = f"{network}_{training}"
    if name not in SHA256:
        raise ValueError(f"no published weights {name!r}; known: {', '.join(SHA256)}")
    return name


def weights_path(network: str, training: str, url: str, *, download: bool = True) -> Path:
    """The verified file of ``network`` (``vgn``/``giga``) trained on ``training``
    (``packed``/``pile``), fetched from ``url`` first when missing and allowed.

    Raises:
        WeightsError: missing (and not fetched), unreachable, or not the published file; the
            message is one line naming the file and the fix.
    """
    name = weights_name(network, training)
    path = models_dir() / FOLDER / f"{name}.pt"
    if not path.is_file():
        if models_dir_is_set():
            raise WeightsError(
                f"{shown_path(path)} is missing: HSQ_MODELS_DIR must hold {FOLDER}/{name}.pt "
                "(see docs/learned-baselines.md), or unset it to download the published weights"
            )
        if not download:
            raise WeightsError(f"{shown_path(path)} is missing and downloading is off")
        _download(f"{url.rstrip('/')}/{name}.pt", path, SHA256[name])
    stat = path.stat()
    digest = _sha256(str(path), stat.st_size, stat.st_mtime_ns)
    if digest != SHA256[name]:
        raise WeightsError(
            f"{shown_path(path)} is not the published {name} weights (sha256 {digest[:12]}..., "
            f"expected {SHA256[name][:12]}...): delete it to download it again, or replace it"
        )
    return path


def _download(url: str, path: Path, sha256: str) -> None:
    from hsqbench.assets.config import DownloadConfig
    from hsqbench.assets.download import DownloadError, fetch

    path.parent.mkdir(parents=True, exist_ok=True)
    print(f"downloading {path.name} from {url}", file=sys.stderr, flush=True)
    try:
        fetch(url, path, DownloadConfig(min_archive_bytes=MIN_BYTES), sha256, progress=True)
    except DownloadError as exc:
        raise WeightsError(
            f"cannot fetch the {path.stem} weights: {exc}; put the file at {shown_path(path)} "
            "or set HSQ_MODELS_DIR to a folder holding giga/*.pt"
        ) from exc


@functools.lru_cache(maxsize=16)
def _sha256(path: str, size: int, mtime_ns: int) -> str:
    """sha256 of a file, computed once per size and modification time."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def state_dict_problems(expected: dict[str, Any], given: dict[str, Any]) -> list[str]:
    """How a state dict ``given`` differs from a module's ``expected`` (names -> tensors):
    missing keys, unexpected keys, shape mismatches; empty when they fit exactly."""
    problems = [f"missing {k}" for k in expected if k not in given]
    problems += [f"unexpected {k}" for k in given if k not in expected]
    problems += [
        f"{k} has shape {tuple(given[k].shape)}, the network {tuple(v.shape)}"
        for k, v in expected.items()
        if k in given and tuple(given[k].shape) != tuple(v.shape)
    ]
    return problems


def load_strict(module: Any, path: Path) -> Any:
    """``module`` with the state dict of ``path`` loaded, every key and shape checked.

    Raises:
        WeightsError: the file is not a state dict, or does not fit ``module`` (the message
            names the file and the first differences).
    """
    import torch

    try:
        given = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises many types for a bad file
        raise WeightsError(f"{shown_path(path)} is not a torch state dict: {exc}") from exc
    if not isinstance(given, dict):
        raise WeightsError(f"{shown_path(path)} holds a {type(given).__name__}, not a state dict")
    problems = state_dict_problems(module.state_dict(), given)
    if problems:
        shown = "; ".join(problems[:4]) + (
            f"; ... {len(problems) - 4} more" if len(problems) > 4 else ""
        )
        raise WeightsError(
            f"{shown_path(path)} does not fit the {type(module).__name__} network "
            f"({len(problems)} difference(s): {shown})"
        )
    module.load_state_dict(given, strict=True)
    return module.eval()
