"""``hsqbench view --web`` in a real browser (slow: about a minute with software WebGL): headless
Chromium opens the printed address, fetches the recording and its layout, and renders the
episode (many colours), not Rerun's Welcome page (about 80 colours, measured)."""

from __future__ import annotations

import base64
import json
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

#: Distinct colours (RGB quantised to 16 levels) above which a screenshot shows a scene: Rerun's
#: Welcome page has about 80, a rendered episode several hundred.
MIN_COLOURS = 300
#: Seconds from navigation to the screenshot: the viewer's WebAssembly and the recording load
#: in about 30 s with software WebGL.
SETTLE_S = 45


def _episode(path: Path) -> None:
    """A recording with what an episode has: a coloured cloud, a camera with a depth image, the
    workspace and an outcome, on the sim_time timeline."""
    import rerun as rr

    rng = np.random.default_rng(0)
    rec = rr.RecordingStream("hsqbench")
    rec.save(path)
    rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    rec.log("world/workspace", rr.Boxes3D(mins=[[0.3, -0.2, 0.0]], sizes=[[0.4, 0.4, 0.3]]))
    rec.set_time("sim_time", duration=0.0)
    points = rng.uniform([0.3, -0.2, 0.0], [0.7, 0.2, 0.1], size=(20000, 3))
    rec.log(
        "world/cloud", rr.Points3D(points, colors=rng.integers(0, 255, (20000, 3)), radii=0.004)
    )
    rec.log("world/cameras/left", rr.Transform3D(translation=[0.62, 0.78, 0.55]))
    rec.log("world/cameras/left", rr.Pinhole(focal_length=60.0, width=64, height=48))
    depth = rng.uniform(0.5, 1.0, (48, 64)).astype(np.float32)
    rec.log("world/cameras/left/depth", rr.DepthImage(depth, meter=1.0))
    rec.log("outcome", rr.TextDocument("## attempt 1: success"))
    rec.flush()
    rec.disconnect()


def _screenshot(url: str, profile: Path) -> bytes:
    """A PNG of ``url`` after :data:`SETTLE_S` seconds in headless Chromium (DevTools protocol)."""
    from websockets.sync.client import connect

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    browser = subprocess.Popen(
        [
            shutil.which("chromium") or "chromium",
            "--headless=new",
            "--no-sandbox",
            "--disable-dev-shm-usage",
            "--enable-unsafe-swiftshader",
            "--use-angle=swiftshader",
            "--ignore-gpu-blocklist",
            "--window-size=1400,900",
            f"--remote-debugging-port={port}",
            f"--user-data-dir={profile}",
            "about:blank",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        for _ in range(200):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=2) as r:
                    targets = json.load(r)
                break
            except OSError:
                time.sleep(0.3)
        page = next(t for t in targets if t["type"] == "page")
        with connect(page["webSocketDebuggerUrl"], max_size=None, open_timeout=60) as ws:

            def call(n: int, method: str, **params) -> dict:
                ws.send(json.dumps({"id": n, "method": method, "params": params}))
                while True:
                    message = json.loads(ws.recv(timeout=300))
                    if message.get("id") == n:
                        return message["result"]

            call(1, "Page.navigate", url=url)
            time.sleep(SETTLE_S)
            return base64.b64decode(call(2, "Page.captureScreenshot", format="png")["data"])
    finally:
        browser.terminate()
        browser.wait(timeout=30)


@pytest.mark.skipif(shutil.which("chromium") is None, reason="needs chromium (apt-get install)")
def test_the_printed_address_opens_the_episode_in_a_browser(tmp_path):
    pytest.importorskip("websockets")
    from PIL import Image

    recording = tmp_path / "episode.rrd"
    _episode(recording)
    command = [sys.executable, "-m", "hsqbench.cli", "view", str(recording), "--web"]
    view = subprocess.Popen(
        [*command, "--web-port", "0", "--rrd-port", "0"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        line = ""
        while not line.startswith("open "):
            line = view.stdout.readline()
            assert line, "view --web ended without printing an address"
        png = _screenshot(line[5:].strip(), tmp_path / "profile")
    finally:
        view.terminate()
        view.wait(timeout=30)
    (tmp_path / "screenshot.png").write_bytes(png)
    image = np.asarray(Image.open(tmp_path / "screenshot.png").convert("RGB"))
    colours = len(np.unique(image.reshape(-1, 3) // 16, axis=0))
    assert colours > MIN_COLOURS, f"{colours} colours: not the episode ({tmp_path})"
