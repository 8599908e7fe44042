"""YCB objects downloaded when needed (hsqbench.assets.on_demand), from a local server."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from hsqbench.assets.download import DownloadError
from hsqbench.assets.library import object_names, object_spec, ycb_names
from hsqbench.assets.on_demand import fetch_missing, missing_ycb
from hsqbench.settings import SettingError, default_ycb_dir, ycb_dir
from tests.ycb_server import archives, serve


@pytest.fixture
def server(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    with serve() as httpd:
        monkeypatch.setenv("HSQ_YCB_URL", httpd.base_url)
        yield httpd


def test_without_hsq_ycb_dir_the_library_is_the_download_table(server):
    from hsqbench.assets.library import default_config

    table = [o.name for o in default_config().download.objects]
    assert ycb_names() == table and len(table) >= 15
    assert object_names("ycb") == []  # nothing downloaded yet
    assert missing_ycb(["proc_box", "mug", "mug"], default_config()) == ["mug"]


def test_missing_objects_are_fetched_once_into_the_data_folder(server):
    server.files.update(archives("foam_brick", "tomato_soup_can"))
    got = fetch_missing(["foam_brick", "proc_box", "tomato_soup_can"], progress=False)
    assert got == ["foam_brick", "tomato_soup_can"]
    assert sorted(name for name, _ in server.requests) == sorted(server.files)
    folder = default_ycb_dir()
    assert Path(os.environ["HSQ_DATA_DIR"]) / "ycb" == folder
    assert ycb_dir() == folder.resolve()
    assert object_names("ycb") == ["tomato_soup_can", "foam_brick"]  # the table's order
    assert object_spec("foam_brick").mesh_path == (folder / "foam_brick" / "textured.obj").resolve()
    assert "CC BY 4.0" in (folder / "ATTRIBUTION.md").read_text()
    server.requests.clear()
    assert fetch_missing(["foam_brick", "tomato_soup_can"], progress=False) == []
    assert server.requests == []


def test_a_users_own_folder_is_never_written(server, tmp_path, monkeypatch):
    monkeypatch.setenv("HSQ_YCB_DIR", str(tmp_path / "mine"))
    (tmp_path / "mine").mkdir()
    assert fetch_missing(["foam_brick"], progress=False) == []
    assert server.requests == [] and list((tmp_path / "mine").iterdir()) == []


def test_a_failed_download_names_the_object_and_how_to_resume(server):
    server.files.update(archives("foam_brick"))
    with pytest.raises(DownloadError) as err:
        fetch_missing(["foam_brick", "mug"], progress=False)
    message = str(err.value)
    assert "1 YCB object(s) could not be downloaded" in message
    assert "mug: HTTP 404" in message and "025_mug_google_16k.tgz" in message
    assert "run the same command again to resume" in message and "HSQ_YCB_URL" in message
    assert (default_ycb_dir() / "foam_brick" / "textured.obj").is_file()  # the other one landed


def test_no_ycb_folder_message_names_every_way_and_no_machine_path(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    with pytest.raises(SettingError) as err:
        ycb_dir()
    message = str(err.value)
    for way in ("hsqbench benchmark", "hsqbench assets download", "export HSQ_YCB_DIR=DIR"):
        assert way in message
    assert "shared" not in message and "/work" not in message


def test_trial_downloads_a_missing_ycb_object_as_benchmark_does(server, monkeypatch, capsys):
    import hsqbench.sim.trial as trial
    from hsqbench.cli import main
    from hsqbench.sim.outcome import Attempt, Outcome, TrialResult

    server.files.update(archives("foam_brick"))
    ran = []

    def fake_trial(obj, seed, planner, config, recorder=None):
        ran.append(obj)
        return TrialResult(obj, seed, planner, [Attempt(Outcome.NO_GRASP_FOUND)])

    monkeypatch.setattr(trial, "run_isolated_trial", fake_trial)
    assert main(["trial", "--object", "foam_brick", "--sensor", "surface"]) == 0
    assert ran == ["foam_brick"]
    line = capsys.readouterr().err.splitlines()[0]  # then the download's progress
    assert line.startswith("HSQ_YCB_DIR is not set: downloading 1 YCB object(s) into ")
    assert line.endswith("(CC BY 4.0, see its ATTRIBUTION.md): foam_brick")
    assert (default_ycb_dir() / "foam_brick" / "textured.obj").is_file()
