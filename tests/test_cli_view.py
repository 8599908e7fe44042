"""``hsqbench view``: refuses missing or unreadable files, says how to open a recording without a
display, and starts the viewer when there is one."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.cli import main
from hsqbench.commands import view


@pytest.fixture(scope="module")
def small_rrd(tmp_path_factory):
    """A tiny valid recording with an outcome on the sim_time timeline."""
    import rerun as rr

    path = tmp_path_factory.mktemp("view") / "episode.rrd"
    rec = rr.RecordingStream("hsqbench")
    rec.save(path)
    rec.log("world/cloud", rr.Points3D(np.zeros((3, 3))), static=True)
    for k in range(3):
        rec.set_time("sim_time", duration=0.5 * k)
        rec.log("world/objects/box", rr.Transform3D(translation=[0.0, 0.0, 0.1 * k]))
    rec.log("outcome", rr.TextDocument("## attempt 1: dropped\n\n- detail: slipped"))
    rec.flush()
    rec.disconnect()
    return path


@pytest.fixture
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(view.sys, "platform", "linux")


def test_missing_file_is_an_error(tmp_path, capsys):
    missing = tmp_path / "nope.rrd"
    assert main(["view", str(missing)]) == 2
    err = capsys.readouterr().err
    assert "no such recording" in err and str(missing) in err


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("garbage.rrd", b"not a recording at all", "Rerun cannot read"),
        ("empty.rrd", b"", "Rerun cannot read"),
        ("episode.txt", b"text", "must end in .rrd"),
    ],
)
def test_unreadable_files_are_errors(tmp_path, capsys, name, content, message):
    path = tmp_path / name
    path.write_bytes(content)
    assert main(["view", str(path)]) == 2
    assert message in capsys.readouterr().err


def test_no_display_prints_how_to_open_it(small_rrd, no_display, capsys, monkeypatch):
    started = []
    monkeypatch.setattr(view.subprocess, "Popen", lambda *a, **k: started.append(a))
    assert main(["view", str(small_rrd)]) == 0
    out = capsys.readouterr().out
    assert "no display" in out
    assert f"rerun {small_rrd}" in out
    assert "pip install rerun-sdk==" in out
    assert "sim_time 0.00-1.00 s" in out and "last outcome: attempt 1: dropped" in out
    assert started == []


def test_display_starts_the_viewer(small_rrd, monkeypatch, capsys):
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(view, "viewer_executable", lambda: "/opt/bin/rerun")
    started = []
    monkeypatch.setattr(view.subprocess, "Popen", lambda args, **k: started.append(args))
    assert main(["view", str(small_rrd)]) == 0
    assert started == [["/opt/bin/rerun", str(small_rrd)]]
    assert "opened" in capsys.readouterr().out


def test_missing_viewer_says_so(small_rrd, monkeypatch, capsys):
    monkeypatch.setenv("DISPLAY", ":0")
    monkeypatch.setattr(view, "viewer_executable", lambda: None)
    monkeypatch.setattr(view.subprocess, "Popen", lambda *a, **k: pytest.fail("no viewer to start"))
    assert main(["view", str(small_rrd)]) == 0
    out = capsys.readouterr().out
    assert "not installed" in out and "pip install rerun-sdk==" in out


def test_web_serves_with_the_rerun_executable(small_rrd, monkeypatch, capsys):
    monkeypatch.setattr(view, "viewer_executable", lambda: "/opt/bin/rerun")
    calls = []
    monkeypatch.setattr(view.subprocess, "call", lambda args: calls.append(args) or 0)
    assert main(["view", str(small_rrd), "--web", "--port", "9191"]) == 0
    assert calls == [
        ["/opt/bin/rerun", "--web-viewer", "--web-viewer-port", "9191", str(small_rrd)]
    ]
    assert main(["view", str(small_rrd), "--web", "--port", "0"]) == 2


def test_has_display():
    assert not view.has_display({}, "linux")
    assert view.has_display({"DISPLAY": ":1"}, "linux")
    assert view.has_display({"WAYLAND_DISPLAY": "wayland-0"}, "linux")
    assert not view.has_display({"DISPLAY": ""}, "linux")
    assert view.has_display({}, "darwin") and view.has_display({}, "win32")


def test_the_installed_viewer_is_found():
    exe = view.viewer_executable()
    assert exe is not None and exe.endswith("rerun")
