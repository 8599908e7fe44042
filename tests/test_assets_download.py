"""YCB download against a local HTTP server on 127.0.0.1 (hsqbench.assets.download).

The archives are built in the test from small synthetic meshes, in the official layout; nothing
contacts the internet.
"""

from __future__ import annotations

import dataclasses
import hashlib
import io
import os
import tarfile

import pytest

from hsqbench.assets.config import DownloadConfig, YcbObject, load_assets_config
from hsqbench.assets.download import (
    DownloadError,
    archive_key,
    archive_name,
    download_ycb,
    fetch,
)
from hsqbench.assets.ycb import read_objects_csv
from tests.ycb_server import serve, synthetic_archive, textured_obj, ycb_object

SOURCE = "foam_brick"


@pytest.fixture
def server():
    with serve() as httpd:
        yield httpd


@pytest.fixture(scope="module")
def archive() -> bytes:
    """A .tgz laid out like the official one, made from a synthetic box."""
    return synthetic_archive(SOURCE)


def _object(name: str) -> YcbObject:
    return ycb_object(name)


def _config(**kwargs) -> DownloadConfig:
    return dataclasses.replace(load_assets_config().download, **kwargs)


def test_download_writes_the_ycb_layout(tmp_path, server, archive):
    server.files[archive_name(_object(SOURCE))] = archive
    report = download_ycb(tmp_path, _config(), [SOURCE], base_url=server.base_url, progress=False)
    assert report.downloaded == [SOURCE] and not report.failed
    entries = read_objects_csv(tmp_path)
    assert [(e.name, e.ycb_id, e.mass_kg) for e in entries] == [(SOURCE, "061", 0.028)]
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        for name in ("textured.obj", "textured.mtl", "texture_map.png"):
            member = tar.extractfile(f"061_{SOURCE}/google_16k/{name}")
            assert (tmp_path / SOURCE / name).read_bytes() == member.read()
    assert not (tmp_path / SOURCE / "kinbody.xml").exists()
    assert "CC BY 4.0" in (tmp_path / "ATTRIBUTION.md").read_text()
    assert not (tmp_path / ".download").exists()  # archive removed, no partial files left
    # Objects already present are skipped without a request.
    server.requests.clear()
    again = download_ycb(tmp_path, _config(), [SOURCE], base_url=server.base_url, progress=False)
    assert again.skipped == [SOURCE] and server.requests == []


def test_missing_archive_reports_the_http_status_and_url(tmp_path, server):
    report = download_ycb(tmp_path, _config(), ["mug"], base_url=server.base_url, progress=False)
    assert "HTTP 404" in report.failed["mug"]
    assert "025_mug_google_16k.tgz" in report.failed["mug"]
    assert not (tmp_path / "mug").exists()
    assert read_objects_csv(tmp_path) == []


def test_corrupt_archive_is_rejected_and_removed(tmp_path, server):
    server.files[archive_name(_object(SOURCE))] = os.urandom(20000)
    report = download_ycb(tmp_path, _config(), [SOURCE], base_url=server.base_url, progress=False)
    assert "not a valid .tgz" in report.failed[SOURCE]
    assert not (tmp_path / SOURCE).exists()
    assert not any((tmp_path / ".download").glob("*"))  # fetched again on the next run
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".tmp")]


def test_archive_without_the_mesh_is_rejected(tmp_path, server):
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz") as tar:
        data = os.urandom(20000)
        info = tarfile.TarInfo("061_foam_brick/google_16k/texture_map.png")
        info.size = len(data)
        tar.addfile(info, io.BytesIO(data))
    server.files[archive_name(_object(SOURCE))] = buffer.getvalue()
    report = download_ycb(tmp_path, _config(), [SOURCE], base_url=server.base_url, progress=False)
    assert "textured.obj" in report.failed[SOURCE]


def test_configured_sha256_is_checked(tmp_path, server, archive):
    server.files[archive_name(_object(SOURCE))] = archive
    wrong = _config(sha256={SOURCE: "0" * 64})
    report = download_ycb(tmp_path, wrong, [SOURCE], base_url=server.base_url, progress=False)
    assert "sha256" in report.failed[SOURCE]
    right = _config(sha256={SOURCE: hashlib.sha256(archive).hexdigest()})
    report = download_ycb(tmp_path, right, [SOURCE], base_url=server.base_url, progress=False)
    assert report.downloaded == [SOURCE]


def test_too_small_answer_is_not_taken_for_an_archive(tmp_path, server):
    server.files[archive_name(_object(SOURCE))] = b"<html>moved</html>"
    report = download_ycb(tmp_path, _config(), [SOURCE], base_url=server.base_url, progress=False)
    assert "only 18 bytes" in report.failed[SOURCE]


def test_interrupted_download_resumes_with_a_range_request(tmp_path, server, archive):
    target = tmp_path / "a.tgz"
    server.files["a.tgz"] = archive
    half = len(archive) // 2
    (tmp_path / "a.tgz.part").write_bytes(archive[:half])
    fetch(f"{server.base_url}/a.tgz", target, _config(), None, progress=False)
    assert server.requests == [("a.tgz", f"bytes={half}-")]
    assert target.read_bytes() == archive
    assert not (tmp_path / "a.tgz.part").exists()


def test_server_without_ranges_restarts_from_zero(tmp_path, server, archive):
    server.ranges = False
    server.files["a.tgz"] = archive
    (tmp_path / "a.tgz.part").write_bytes(b"stale bytes")
    fetch(f"{server.base_url}/a.tgz", tmp_path / "a.tgz", _config(), None, progress=False)
    assert (tmp_path / "a.tgz").read_bytes() == archive


def test_unreachable_server_names_the_url(tmp_path, server):
    url = server.base_url
    server.shutdown()
    server.server_close()
    with pytest.raises(DownloadError, match=r"cannot reach http://127\.0\.0\.1"):
        fetch(f"{url}/a.tgz", tmp_path / "a.tgz", _config(timeout_s=5.0), None, progress=False)


def test_unknown_object_lists_the_known_ones(tmp_path):
    with pytest.raises(
        ValueError, match=r"unknown YCB object\(s\) \['teapot'\]; known: cracker_box"
    ):
        download_ycb(tmp_path, _config(), ["teapot"], base_url="http://127.0.0.1:9", progress=False)


def test_downloaded_folder_works_as_hsq_ycb_dir(tmp_path, server, archive, monkeypatch):
    from hsqbench.assets.library import object_names, object_spec

    server.files[archive_name(_object(SOURCE))] = archive
    download_ycb(tmp_path / "ycb", _config(), [SOURCE], base_url=server.base_url, progress=False)
    monkeypatch.setenv("HSQ_YCB_DIR", str(tmp_path / "ycb"))
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))
    assert object_names("ycb") == [SOURCE]
    spec = object_spec(SOURCE)
    assert spec.mass_kg == pytest.approx(0.028)
    assert spec.mesh_path == (tmp_path / "ycb" / SOURCE / "textured.obj").resolve()


def test_archive_keys_follow_the_official_names():
    assert archive_key(YcbObject("cracker_box", "003", 0.411)) == "003_cracker_box"
    assert archive_name(YcbObject("a_cups", "065-a", 0.013)) == "065-a_cups_google_16k.tgz"
    assert archive_key(YcbObject("b_toy_airplane", "072-b", 0.114)) == "072-b_toy_airplane"


def test_a_lettered_object_downloads_from_its_hyphenated_archive(tmp_path, server):
    import trimesh

    server.files["065-a_cups_google_16k.tgz"] = synthetic_archive(
        "a_cups", trimesh.creation.cylinder(radius=0.03, height=0.05)
    )
    report = download_ycb(tmp_path, _config(), ["a_cups"], base_url=server.base_url, progress=False)
    assert report.downloaded == ["a_cups"], report.failed
    assert [(e.name, e.ycb_id) for e in read_objects_csv(tmp_path)] == [("a_cups", "065-a")]


def test_progress_in_a_log_is_one_line_per_object(tmp_path, server, archive, capsys):
    server.files[archive_name(_object(SOURCE))] = archive
    download_ycb(tmp_path, _config(), [SOURCE, "mug"], base_url=server.base_url)
    err = capsys.readouterr().err
    assert "\r" not in err
    assert err.splitlines() == [
        "YCB 1/2: downloading 061_foam_brick_google_16k.tgz",
        "YCB 2/2: downloading 025_mug_google_16k.tgz",
    ]


def test_synthetic_obj_has_a_texture_coordinate_per_vertex():
    import trimesh

    text = textured_obj(trimesh.creation.box(extents=(0.1, 0.2, 0.3)))
    assert text.count("\nv ") == text.count("\nvt ") == 8
    assert min(float(line.split()[3]) for line in text.splitlines() if line.startswith("v ")) == 0
