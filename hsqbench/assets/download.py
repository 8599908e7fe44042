"""Source (b): fetch the Google 16k YCB scans (``hsqbench assets download``).

Each object is the archive ``{base_url}/{key}_google_16k.tgz``, which holds
``{key}/google_16k/textured.obj``, ``textured.mtl`` and ``texture_map.png``; the key is
``{ycb_id}_{name}`` (``003_cracker_box``), or ``065-a_cups`` for the lettered variants. The download
writes the layout that ``HSQ_YCB_DIR`` expects (see ``hsqbench.assets.ycb``): ``DEST/<name>/...``,
``DEST/objects.csv`` (name, ycb_id, mass_kg) and ``DEST/ATTRIBUTION.md``.

Checks: HTTP status, received size against Content-Length and a minimum size, the optional
sha256 of ``download.sha256`` in ``configs/assets.yaml``, the archive's integrity and members,
and that the extracted mesh loads. Robustness: the archive is streamed to ``.part`` and renamed
when complete; an interrupted ``.part`` is resumed with an HTTP Range request; each object is
extracted into a temporary folder renamed into place; objects already present are skipped.

The YCB Object and Model Set (Calli et al., IEEE RAM 2015) is licensed CC BY 4.0: the
attribution file written next to the meshes must stay with them.
"""

from __future__ import annotations

import csv
import hashlib
import io
import os
import shutil
import sys
import tarfile
import tempfile
import urllib.error
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

from hsqbench.assets.config import DownloadConfig, YcbObject
from hsqbench.assets.ycb import CSV_COLUMNS, CSV_NAME, MESH_NAME, MTL_NAME, TEXTURE_NAME

PARTIAL_DIR = ".download"
MEMBERS = (MESH_NAME, MTL_NAME, TEXTURE_NAME)
ATTRIBUTION = """# YCB object models

These meshes and textures are the Google 16k scans of the YCB Object and Model Set:
B. Calli, A. Walsman, A. Singh, S. Srinivasa, P. Abbeel, A. M. Dollar,
"Benchmarking in Manipulation Research: The YCB Object and Model Set and Benchmarking Protocols",
IEEE Robotics and Automation Magazine, 2015. The models are distributed under CC BY 4.0.
Downloaded by `hsqbench assets download` from {base_url}.

Any results or images made with these models should credit the YCB Object and Model Set.
"""


class DownloadError(RuntimeError):
    """An archive could not be fetched, verified or extracted (the message says which and why)."""


@dataclass
class DownloadReport:
    downloaded: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)
    failed: dict[str, str] = field(default_factory=dict)


def archive_key(obj: YcbObject) -> str:
    """The object's key in the official set: ``003_cracker_box``; lettered variants join with a
    hyphen, ``065-a_cups`` (id ``065-a``, name ``a_cups``)."""
    number, _, letter = obj.ycb_id.partition("-")
    if letter and obj.name.startswith(f"{letter}_"):
        return f"{number}-{obj.name}"
    return f"{obj.ycb_id}_{obj.name}"


def archive_name(obj: YcbObject) -> str:
    return f"{archive_key(obj)}_google_16k.tgz"


def archive_url(base_url: str, obj: YcbObject) -> str:
    return f"{base_url.rstrip('/')}/{archive_name(obj)}"


def select_objects(config: DownloadConfig, names: list[str] | None) -> list[YcbObject]:
    known = {o.name: o for o in config.objects}
    if not names:
        return list(config.objects)
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"unknown YCB object(s) {unknown}; known: {', '.join(known)}")
    return [known[n] for n in names]


def is_present(folder: Path) -> bool:
    """An object folder counts as present when its mesh loads with at least one triangle."""
    return _mesh_loads(folder / MESH_NAME) is None


def _mesh_loads(path: Path) -> str | None:
    """``None`` when ``path`` loads as a non-empty triangle mesh, else the reason."""
    import trimesh

    if not path.is_file():
        return f"{path} is missing"
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as exc:
        return f"{path} does not load ({type(exc).__name__}: {exc})"
    if not isinstance(mesh, trimesh.Trimesh) or len(mesh.faces) == 0:
        return f"{path} holds no triangles"
    return None


def fetch(
    url: str, target: Path, config: DownloadConfig, expected_sha256: str | None, progress: bool
) -> None:
    """Download ``url`` to ``target`` through ``target.part`` (resumed if present), with checks."""
    part = target.with_name(target.name + ".part")
    offset = part.stat().st_size if part.is_file() else 0
    response = _open(url, part, offset, config)
    with response:
        status = response.status
        if status not in (200, 206):
            raise DownloadError(f"HTTP {status} for {url}")
        if status == 200:
            offset = 0  # the server ignored the Range request: start from the beginning
        length = response.headers.get("Content-Length")
        expected = offset + int(length) if length is not None else None
        with part.open("ab" if status == 206 else "wb") as out:
            _stream(response, out, url, config, _bar(expected, offset, target.name, progress))
    _check_part(part, url, expected, config, expected_sha256)
    os.replace(part, target)


def _open(url: str, part: Path, offset: int, config: DownloadConfig) -> Any:
    """The server's response to a GET of ``url``, asking for the bytes after ``offset`` (what
    ``part`` holds already); a ``part`` the server cannot resume is deleted."""
    request = urllib.request.Request(url, headers={"User-Agent": "hsqbench"})
    if offset:
        request.add_header("Range", f"bytes={offset}-")
    try:
        return urllib.request.urlopen(request, timeout=config.timeout_s)
    except urllib.error.HTTPError as exc:
        if exc.code == 416 and offset:  # the .part cannot be resumed: start again next time
            part.unlink()
        raise DownloadError(f"HTTP {exc.code} {exc.reason} for {url}") from exc
    except (urllib.error.URLError, OSError) as exc:
        reason = getattr(exc, "reason", exc)
        raise DownloadError(
            f"cannot reach {url}: {reason}; check the connection or --base-url"
        ) from exc


def _bar(expected: int | None, offset: int, name: str, progress: bool) -> Any:
    """A byte progress bar on a terminal; a log gets one line per object, so none there."""
    from tqdm import tqdm

    return tqdm(
        total=expected,
        initial=offset,
        unit="B",
        unit_scale=True,
        desc=name,
        disable=not (progress and sys.stderr.isatty()),
        leave=False,
    )


def _stream(response: Any, out: BinaryIO, url: str, config: DownloadConfig, bar: Any) -> None:
    """Copy the response body to ``out`` chunk by chunk, advancing ``bar``."""
    with bar:
        while True:
            try:
                chunk = response.read(config.chunk_bytes)
            except OSError as exc:
                raise DownloadError(f"{url}: connection lost ({exc}); run again to resume") from exc
            if not chunk:
                break
            out.write(chunk)
            bar.update(len(chunk))


def _check_part(
    part: Path, url: str, expected: int | None, config: DownloadConfig, sha256: str | None
) -> None:
    """A whole download: the announced size (else keep it to resume), at least an archive's
    size and the configured sha256 (else delete it: resuming cannot repair it)."""
    size = part.stat().st_size
    if expected is not None and size != expected:
        raise DownloadError(
            f"{url}: received {size} bytes, expected {expected}; run again to resume"
        )
    if size < config.min_archive_bytes:
        part.unlink()
        raise DownloadError(
            f"{url}: only {size} bytes (an archive has at least {config.min_archive_bytes}); "
            "is the base URL right?"
        )
    if sha256:
        digest = _sha256(part)
        if digest != sha256.lower():
            part.unlink()
            raise DownloadError(f"{url}: sha256 {digest} does not match the configured {sha256}")


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def extract(archive: Path, obj: YcbObject, dest: Path) -> Path:
    """Extract the three model files of ``archive`` into ``dest/<name>`` (atomically)."""
    try:
        with tarfile.open(archive, "r:gz") as tar:
            members = {}
            for member in tar.getmembers():
                parts = Path(member.name).parts
                if (
                    member.isfile()
                    and len(parts) >= 2
                    and parts[-2] == "google_16k"
                    and parts[-1] in MEMBERS
                ):
                    members[parts[-1]] = member
            missing = [m for m in MEMBERS if m not in members]
            if missing:
                raise DownloadError(f"{archive}: no google_16k/{', '.join(missing)} in the archive")
            tmp = Path(tempfile.mkdtemp(prefix=f".tmp-{obj.name}-", dir=dest))
            try:
                for name, member in members.items():
                    source = tar.extractfile(member)
                    assert source is not None
                    with source, (tmp / name).open("wb") as out:
                        shutil.copyfileobj(source, out)
            except BaseException:
                shutil.rmtree(tmp, ignore_errors=True)
                raise
    except (tarfile.TarError, EOFError, OSError, io.UnsupportedOperation) as exc:
        raise DownloadError(f"{archive}: not a valid .tgz archive ({exc})") from exc
    problem = _mesh_loads(tmp / MESH_NAME)
    if problem is not None:
        shutil.rmtree(tmp, ignore_errors=True)
        raise DownloadError(f"{archive}: extracted mesh is unusable: {problem}")
    final = dest / obj.name
    if final.exists():
        shutil.rmtree(final)
    os.rename(tmp, final)
    return final


def _write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def write_objects_csv(dest: Path, objects: list[YcbObject]) -> None:
    """Write ``objects.csv`` for the objects present in ``dest`` (atomic), keeping config order."""
    rows = [o for o in objects if (dest / o.name / MESH_NAME).is_file()]
    fd, tmp = tempfile.mkstemp(dir=dest, suffix=".csv.tmp")
    with os.fdopen(fd, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(CSV_COLUMNS)
        writer.writerows([o.name, o.ycb_id, f"{o.mass_kg:g}"] for o in rows)
    os.replace(tmp, dest / CSV_NAME)


def download_ycb(
    dest: Path,
    config: DownloadConfig,
    names: list[str] | None = None,
    base_url: str | None = None,
    force: bool = False,
    keep_archives: bool = False,
    progress: bool = True,
) -> DownloadReport:
    """Download the YCB objects ``names`` (default: all of ``config.objects``) into ``dest``.

    Objects already present (mesh loads) are skipped unless ``force``. Failures of single objects
    are collected in the report; the caller decides how to report them.
    """
    from tqdm import tqdm

    objects = select_objects(config, names)
    base_url = base_url or config.base_url
    dest.mkdir(parents=True, exist_ok=True)
    partial = dest / PARTIAL_DIR
    partial.mkdir(exist_ok=True)
    report = DownloadReport()
    terminal = progress and sys.stderr.isatty()
    for i, obj in enumerate(tqdm(objects, desc="YCB objects", unit="obj", disable=not terminal)):
        if not force and is_present(dest / obj.name):
            report.skipped.append(obj.name)
            continue
        if progress and not terminal:
            print(
                f"YCB {i + 1}/{len(objects)}: downloading {archive_name(obj)}",
                file=sys.stderr,
                flush=True,
            )
        archive = partial / archive_name(obj)
        try:
            if not archive.is_file():
                fetch(
                    archive_url(base_url, obj),
                    archive,
                    config,
                    config.sha256.get(obj.name),
                    progress,
                )
            try:
                extract(archive, obj, dest)
            except DownloadError:
                archive.unlink(missing_ok=True)  # a broken archive is fetched again next time
                raise
            if not keep_archives:
                archive.unlink()
            report.downloaded.append(obj.name)
        except DownloadError as exc:
            report.failed[obj.name] = str(exc)
    all_objects = list(config.objects)
    write_objects_csv(dest, all_objects)
    _write_atomic(dest / "ATTRIBUTION.md", ATTRIBUTION.format(base_url=base_url))
    if partial.is_dir() and not any(partial.iterdir()):
        partial.rmdir()
    return report
