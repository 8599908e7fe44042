"""YCB objects fetched when a command needs them: no set-up step before the first benchmark.

When ``HSQ_YCB_DIR`` is unset, the YCB library is the table of ``configs/assets.yaml``
(``download.objects``) and its meshes live in the download folder, ``HSQ_DATA_DIR/ycb``
(default ``assets/ycb`` in the repository). :func:`fetch_missing` downloads the objects of a
list that are not there yet, with the checks, resume and atomic writes of
:mod:`hsqbench.assets.download`, from ``HSQ_YCB_URL`` or the configured official source. With
``HSQ_YCB_DIR`` set it does nothing: a user's own folder is only read.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable

from hsqbench.assets.config import AssetsConfig
from hsqbench.assets.download import DownloadError, download_ycb
from hsqbench.assets.ycb import MESH_NAME
from hsqbench.settings import default_ycb_dir, shown_path, ycb_base_url, ycb_dir_is_set


def missing_ycb(names: Iterable[str], config: AssetsConfig) -> list[str]:
    """The YCB objects of ``names`` that would be downloaded now (none with ``HSQ_YCB_DIR``)."""
    if ycb_dir_is_set():
        return []
    table = {o.name for o in config.download.objects}
    folder = default_ycb_dir()
    # An object folder appears only complete (extracted aside, then renamed): its mesh is enough.
    return [
        n for n in dict.fromkeys(names) if n in table and not (folder / n / MESH_NAME).is_file()
    ]


def fetch_missing(
    names: Iterable[str], config: AssetsConfig | None = None, progress: bool = True
) -> list[str]:
    """Download the YCB objects of ``names`` that the download folder lacks; returns them.

    Raises:
        DownloadError: some could not be fetched; the message names each with its reason, and
            running the command again resumes (finished objects and partial archives are kept).
    """
    from hsqbench.assets.library import default_config

    config = config or default_config()
    missing = missing_ycb(names, config)
    if not missing:
        return []
    folder = default_ycb_dir()
    base_url = ycb_base_url() or config.download.base_url
    print(
        f"HSQ_YCB_DIR is not set: downloading {len(missing)} YCB object(s) into "
        f"{shown_path(folder)} (CC BY 4.0, see its ATTRIBUTION.md): {', '.join(missing)}",
        file=sys.stderr,
        flush=True,
    )
    report = download_ycb(folder, config.download, missing, base_url=base_url, progress=progress)
    if report.failed:
        lines = [f"  {name}: {why}" for name, why in report.failed.items()]
        raise DownloadError(
            f"{len(report.failed)} YCB object(s) could not be downloaded from {base_url}:\n"
            + "\n".join(lines)
            + "\nrun the same command again to resume, set HSQ_YCB_URL to a mirror, or "
            "HSQ_YCB_DIR to a folder that holds them"
        )
    return report.downloaded
