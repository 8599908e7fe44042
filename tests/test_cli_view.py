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


def test_web_prints_the_address_that_opens_the_episode(small_rrd, monkeypatch, capsys):
    """The printed address is the viewer's page with the recording and its layout as url=
    parameters; both are served, byte for byte, while the command waits (no CPU: it blocks)."""
    import urllib.request
    from urllib.parse import parse_qs, urlsplit

    served = {}

    def fetch_while_serving():
        out = capsys.readouterr().out
        address = next(line[5:] for line in out.splitlines() if line.startswith("open "))
        served["address"] = address
        for url in parse_qs(urlsplit(address).query)["url"]:
            with urllib.request.urlopen(url, timeout=10) as response:
                served[url.rsplit("/", 1)[1]] = (
                    response.read(),
                    response.headers["Access-Control-Allow-Origin"],
                )
        with urllib.request.urlopen(address, timeout=10) as page:
            served["page"] = page.read()

    monkeypatch.setattr(view, "_wait", fetch_while_serving)
    assert main(["view", str(small_rrd), "--web", "--web-port", "0", "--rrd-port", "0"]) == 0
    parts = urlsplit(served["address"])
    assert parts.scheme == "http" and parts.hostname == "localhost" and parts.path == "/"
    urls = parse_qs(parts.query)["url"]
    rrd_port = urlsplit(urls[0]).port
    assert urls == [
        f"http://localhost:{rrd_port}/episode.rrd",
        f"http://localhost:{rrd_port}/episode.rbl",
    ]
    assert served["episode.rrd"] == (small_rrd.read_bytes(), "*")
    assert served["episode.rbl"][0][:4] == small_rrd.read_bytes()[:4]  # an rrd-format file
    assert b"Rerun" in served["page"] and parts.port != rrd_port
    out = capsys.readouterr().out  # each file sent is said (a remote user sees the tunnel works)
    assert "sent episode.rrd to the browser at 127.0.0.1" in out and "sent episode.rbl" in out


def test_web_ports_are_checked(small_rrd, capsys):
    assert main(["view", str(small_rrd), "--web", "--web-port", "70000"]) == 2
    assert "--web-port must be a TCP port 0-65535" in capsys.readouterr().err
    assert main(["view", str(small_rrd), "--web", "--web-port", "9999", "--rrd-port", "9999"]) == 2
    assert "give two ports" in capsys.readouterr().err


def test_the_old_port_option_still_works_with_a_note(small_rrd, monkeypatch, capsys):
    monkeypatch.setattr(view, "_serve_web", lambda summary, web, rrd: print(f"ports {web} {rrd}"))
    assert main(["view", str(small_rrd), "--web", "--port", "9191"]) == 0
    captured = capsys.readouterr()
    assert "--port is deprecated, use --web-port" in captured.err
    assert f"ports 9191 {view.RRD_PORT}" in captured.out


def test_has_display():
    assert not view.has_display({}, "linux")
    assert view.has_display({"DISPLAY": ":1"}, "linux")
    assert view.has_display({"WAYLAND_DISPLAY": "wayland-0"}, "linux")
    assert not view.has_display({"DISPLAY": ""}, "linux")
    assert view.has_display({}, "darwin") and view.has_display({}, "win32")


def test_the_installed_viewer_is_found():
    exe = view.viewer_executable()
    assert exe is not None and exe.endswith("rerun")
