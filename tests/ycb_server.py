"""A stand-in for the YCB download server, for tests: archives in the official layout, built
from small synthetic meshes, served by an HTTP server on 127.0.0.1 (nothing leaves the machine).

An archive ``{key}_google_16k.tgz`` holds ``{key}/google_16k/textured.obj`` (with texture
coordinates), ``textured.mtl``, ``texture_map.png`` and, as the real ones do, files hsqbench
ignores (``kinbody.xml``)::

    from tests.ycb_server import serve, synthetic_archive
"""

from __future__ import annotations

import contextlib
import http.server
import io
import tarfile
import threading
from collections.abc import Iterator

import numpy as np
import trimesh
from PIL import Image

from hsqbench.assets.config import YcbObject, load_assets_config
from hsqbench.assets.download import archive_key, archive_name

# Small shapes with the sizes of the real objects (metres, z up, base on z = 0).
SHAPES = {
    "foam_brick": lambda: trimesh.creation.box(extents=(0.05, 0.075, 0.05)),
    "tomato_soup_can": lambda: trimesh.creation.cylinder(radius=0.034, height=0.10, sections=24),
    "apple": lambda: trimesh.creation.icosphere(subdivisions=2, radius=0.037),
}


def ycb_object(name: str) -> YcbObject:
    return next(o for o in load_assets_config().download.objects if o.name == name)


def textured_obj(mesh: trimesh.Trimesh) -> str:
    """OBJ text of ``mesh`` (base moved to z = 0) with one texture coordinate per vertex."""
    vertices = mesh.vertices - [0.0, 0.0, mesh.vertices[:, 2].min()]
    span = np.ptp(vertices[:, :2], axis=0)
    uv = (vertices[:, :2] - vertices[:, :2].min(axis=0)) / np.where(span > 0, span, 1.0)
    lines = ["mtllib textured.mtl", "usemtl material_0"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"vt {u:.6f} {v:.6f}" for u, v in uv]
    lines += [f"f {a}/{a} {b}/{b} {c}/{c}" for a, b, c in mesh.faces + 1]
    return "\n".join(lines) + "\n"


def _png(seed: int) -> bytes:
    """A 64 x 64 noise texture (noise does not compress: the archive passes the size check)."""
    pixels = np.random.default_rng(seed).integers(0, 256, (64, 64, 3), dtype=np.uint8)
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, format="PNG")
    return buffer.getvalue()


def synthetic_archive(name: str, mesh: trimesh.Trimesh | None = None) -> bytes:
    """The .tgz of YCB object ``name`` in the official layout, its mesh from :data:`SHAPES`."""
    mesh = mesh if mesh is not None else SHAPES[name]()
    key = archive_key(ycb_object(name))
    files = {
        "textured.obj": textured_obj(mesh).encode(),
        "textured.mtl": b"newmtl material_0\nKd 1 1 1\nmap_Kd texture_map.png\n",
        "texture_map.png": _png(len(name)),
        "kinbody.xml": b"<KinBody/>",  # in the real archives too; not extracted
    }
    buffer = io.BytesIO()
    with tarfile.open(fileobj=buffer, mode="w:gz", compresslevel=1) as tar:
        for member, data in files.items():
            info = tarfile.TarInfo(f"{key}/google_16k/{member}")
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return buffer.getvalue()


def archives(*names: str) -> dict[str, bytes]:
    """``archive file name -> bytes`` for each object, as the server's ``files``."""
    return {archive_name(ycb_object(n)): synthetic_archive(n) for n in names}


class _Handler(http.server.BaseHTTPRequestHandler):
    """Serves ``server.files`` (name -> bytes), honours ``Range: bytes=N-``, logs requests."""

    def do_GET(self):
        name = self.path.rsplit("/", 1)[-1]
        self.server.requests.append((name, self.headers.get("Range")))
        body = self.server.files.get(name)
        if body is None:
            self.send_error(404, "Not Found")
            return
        start = 0
        if self.headers.get("Range") and self.server.ranges:
            start = int(self.headers["Range"].split("=")[1].rstrip("-"))
            self.send_response(206)
            self.send_header("Content-Range", f"bytes {start}-{len(body) - 1}/{len(body)}")
        else:
            self.send_response(200)
        self.send_header("Content-Length", str(len(body) - start))
        self.end_headers()
        self.wfile.write(body[start:])

    def log_message(self, *args):
        pass


@contextlib.contextmanager
def serve() -> Iterator[http.server.ThreadingHTTPServer]:
    """A server on a free port of 127.0.0.1; ``.base_url`` is where its archives are, ``.files``
    what it serves, ``.requests`` what it was asked, ``.ranges`` whether it honours Range."""
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Handler)
    httpd.files, httpd.requests, httpd.ranges = {}, [], True
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    httpd.base_url = f"http://127.0.0.1:{httpd.server_address[1]}/data/google"
    try:
        yield httpd
    finally:
        httpd.shutdown()
        httpd.server_close()
