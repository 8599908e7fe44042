"""Serve a recording to Rerun's web viewer: the address that opens on the episode.

Two servers, each on its own port:

- the recording server (``rrd_port``): a small HTTP server of this process that serves exactly
  the recording and its blueprint (``.rbl``) as files, with the CORS header the viewer's page
  needs to fetch them from another port. Idle, it sleeps in ``select``.
- the viewer (``web_port``): the web viewer's page, served by the Rerun SDK
  (``rerun.serve_web_viewer``), which loads every ``url=`` of its address.

So the address printed is the viewer's with the two files as ``url=`` parameters. Rerun's own
``rerun --web-viewer FILE.rrd`` streams the file through a gRPC server instead, whose address is
not the one it prints first (that opens the Welcome page) and whose server thread keeps a core
busy while no browser is connected; serving files avoids both.
"""

from __future__ import annotations

import http.server
import socket
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from urllib.parse import quote

#: The host name in the printed address (the servers listen on every interface).
HOST = "localhost"


def viewer_url(web_port: int, file_urls: list[str]) -> str:
    """The web viewer's address that opens ``file_urls`` (recording, then blueprint)."""
    query = "&".join(f"url={quote(u, safe='')}" for u in file_urls)
    return f"http://{HOST}:{web_port}/?{query}"


def free_port() -> int:
    """A TCP port nobody listens on now (for a port given as 0)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("", 0))
        return int(s.getsockname()[1])


def _handler(files: Mapping[str, Path]) -> type[http.server.BaseHTTPRequestHandler]:
    class FileHandler(http.server.BaseHTTPRequestHandler):
        """GET (and HEAD) of the served files only; nothing else of the disk is reachable."""

        def _send(self, body: bool) -> None:
            path = files.get(self.path.split("?", 1)[0])
            if path is None:
                self.send_error(404, "only the episode's files are served here")
                return
            data = path.read_bytes()
            self.send_response(200)
            self.send_header("Content-Type", "application/octet-stream")
            self.send_header("Content-Length", str(len(data)))
            self.send_header("Access-Control-Allow-Origin", "*")
            self.end_headers()
            if body:
                self.wfile.write(data)
                # Tells a remote user that the browser (and the ssh tunnel) reached the files.
                print(f"sent {path.name} to the browser at {self.client_address[0]}", flush=True)

        def do_GET(self) -> None:
            self._send(body=True)

        def do_HEAD(self) -> None:
            self._send(body=False)

        def log_message(self, *args: object) -> None:  # quiet: the command prints what matters
            pass

    return FileHandler


@dataclass
class FileServer:
    """The recording server: ``files`` (URL path -> file) on ``port`` until :meth:`close`."""

    server: http.server.ThreadingHTTPServer
    thread: threading.Thread
    urls: list[str]

    @property
    def port(self) -> int:
        return int(self.server.server_address[1])

    def close(self) -> None:
        self.server.shutdown()
        self.server.server_close()
        self.thread.join()


def serve_files(paths: list[Path], port: int) -> FileServer:
    """Serve ``paths`` (by their file names) over HTTP on ``port`` (0: a free one).

    Raises:
        ValueError: the port is taken (naming the option that picks another).
    """
    files = {f"/{quote(p.name)}": p for p in paths}
    try:
        server = http.server.ThreadingHTTPServer(("", port), _handler(files))
    except OSError as exc:
        raise ValueError(
            f"port {port} for the recording is taken ({exc.strerror}): pick another with "
            "--rrd-port, or 0 for a free one"
        ) from None
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, name="rrd-server", daemon=True)
    thread.start()
    port = int(server.server_address[1])
    return FileServer(server, thread, [f"http://{HOST}:{port}{path}" for path in files])


def serve_viewer(web_port: int) -> int:
    """Start the web viewer's page on ``web_port`` (0: a free one); returns the port.

    Raises:
        ValueError: the port is taken (naming the option that picks another).
    """
    import rerun as rr

    port = web_port or free_port()
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        if probe.connect_ex(("127.0.0.1", port)) == 0:
            raise ValueError(
                f"port {port} for the web viewer is taken: pick another with --web-port, or 0 "
                "for a free one"
            )
    rr.serve_web_viewer(web_port=port, open_browser=False)
    return port
