"""Offscreen depth (and segmentation) rendering with one GL context per process.

``mujoco.Renderer`` makes a new GL context (EGL headless) with every renderer; the first
``MjrContext`` in a fresh context then pays for the driver's set-up, about 0.12 s of the 0.25 s a
renderer costs. Each trial compiles a new model, so its ``MjrContext`` (the model's meshes and
textures on the GPU, the offscreen buffers) and ``MjvScene`` must be made again; the GL context
need not. :class:`DepthRenderer` keeps the context for the life of the worker process and makes
only the per-model parts. The images are those of ``mujoco.Renderer`` bit for bit (same buffers,
same depth conversion; ``tests/test_depth_renderer.py`` compares them).

The ``MjrContext`` is kept too, for the next model with the same uploads: presentations of one
object in other poses compile to models that differ only in where the bodies and the keyframe
are (:data:`POSE_FIELDS`), which the context never reads (each draw takes the poses from the
data). Uploading a scene's meshes (the Panda's and the object's, about 400 000 vertices) costs
0.13-0.16 s, and a worker runs the presentations of one object in a row.

Depth: the offscreen buffer holds reversed-Z window depth (``mjDEPTH_ZEROFAR``); planar metric
depth is ``d / (z + c)`` with the perspective projection's ``c = (f + n) / (2 (f - n)) - 1/2``
and ``d = f n / (f - n)`` (near ``n`` and far ``f`` clipping distances of the model, in float32
as OpenGL has them; the division in float64, as MuJoCo's own renderer does it).
"""

from __future__ import annotations

import atexit
import os
from dataclasses import dataclass
from functools import cache
from typing import Any

import mujoco
import numpy as np
from numpy.typing import NDArray

#: Largest number of geoms one image shows (``mujoco.Renderer``'s default).
MAX_GEOM = 10000
#: The model arrays that say where the bodies and the keyframe are, and what follows from that
#: alone: two models that differ only in these share one ``MjrContext`` (module doc).
POSE_FIELDS = frozenset(
    {
        "body_pos",
        "body_quat",
        "body_invweight0",
        "cam_poscom0",
        "light_poscom0",
        "dof_M0",
        "dof_invweight0",
        "dof_length",
        "qpos0",
        "qpos_spring",
        "key_qpos",
        "key_qvel",
        "key_act",
        "key_mpos",
        "key_mquat",
        "key_ctrl",
        "key_time",
    }
)

_context: Any = None
_context_pid = -1


@dataclass
class _Kept:
    """The last ``MjrContext`` made in this process, the model it was made for, and how many
    live renderers draw with it."""

    model: mujoco.MjModel
    mjr: Any
    pid: int
    users: int = 1


_kept: _Kept | None = None


def _free_context() -> None:
    global _context, _kept
    if _kept is not None and _kept.pid == os.getpid() and _context is not None:
        _context.make_current()
        _kept.mjr.free()
    _kept = None
    if _context is not None and _context_pid == os.getpid():
        _context.free()
    _context = None


@cache
def _array_fields() -> tuple[str, ...]:
    """Names of the model's array fields (this MuJoCo version's)."""
    probe = mujoco.MjModel.from_xml_string("<mujoco/>")
    return tuple(n for n in dir(probe) if isinstance(getattr(probe, n, None), np.ndarray))


def same_uploads(a: mujoco.MjModel, b: mujoco.MjModel) -> bool:
    """True when ``a`` and ``b`` differ at most in :data:`POSE_FIELDS`: every other array, the
    visual options and the statistics (fog and shadow distances scale with the extent) equal,
    so one ``MjrContext`` draws both."""
    if a is b:
        return True
    if repr(a.vis) != repr(b.vis) or repr(a.stat) != repr(b.stat):
        return False
    return all(
        np.array_equal(getattr(a, name), getattr(b, name))
        for name in _array_fields()
        if name not in POSE_FIELDS
    )


def _acquire(model: mujoco.MjModel) -> Any:
    """An ``MjrContext`` for ``model``: the kept one when its model has the same uploads, else
    a new one, kept in turn when the kept one has no live renderer (which is then freed)."""
    global _kept
    gl_context()
    pid = os.getpid()
    kept = _kept if _kept is not None and _kept.pid == pid else None
    if kept is not None and same_uploads(kept.model, model):
        kept.users += 1
        return kept.mjr
    mjr = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150.value)
    if kept is None or kept.users == 0:
        if kept is not None:
            kept.mjr.free()
        _kept = _Kept(model, mjr, pid)
    return mjr


def _release(mjr: Any) -> None:
    """A renderer is done with ``mjr``: the kept context stays uploaded, any other is freed."""
    if _kept is not None and mjr is _kept.mjr:
        _kept.users -= 1
    else:
        gl_context()
        mjr.free()


def gl_context() -> Any:
    """This process's GL context (made on first use, freed at exit), current.

    A process forked from one that had a context makes its own: a GL context does not survive
    ``fork``.
    """
    global _context, _context_pid
    if _context is None or _context_pid != os.getpid():
        from mujoco.rendering.classic import gl_context as gl

        if gl.GLContext is None:
            raise RuntimeError(
                "no OpenGL backend for offscreen rendering: set MUJOCO_GL=egl (headless) or "
                "MUJOCO_GL=glfw (with a display)"
            )
        _context = gl.GLContext(640, 480)  # offscreen rendering goes to MuJoCo's own buffer
        _context_pid = os.getpid()
        # Registered after the GL backend's own exit handler, so run before it: the kept
        # MjrContext is freed while the display is still there.
        atexit.register(_free_context)
    _context.make_current()
    return _context


class DepthRenderer:
    """Planar depth and segmentation images of one model at one image size.

    Args:
        model: the compiled model; its offscreen buffer (``<visual><global offwidth offheight>``)
            must hold the image.
        height_px, width_px: image size.
    """

    def __init__(self, model: mujoco.MjModel, height_px: int, width_px: int) -> None:
        self._mjr: Any = None
        off_w, off_h = model.vis.global_.offwidth, model.vis.global_.offheight
        if width_px > off_w or height_px > off_h:
            raise ValueError(
                f"image {width_px} x {height_px} px exceeds the model's offscreen buffer "
                f"{off_w} x {off_h}: raise <visual><global offwidth offheight> in the world file"
            )
        self.model = model
        self.height_px, self.width_px = height_px, width_px
        self._rect = mujoco.MjrRect(0, 0, width_px, height_px)
        self._scene = mujoco.MjvScene(model=model, maxgeom=MAX_GEOM)
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._mjr = _acquire(model)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr)
        self._mjr.readDepthMap = mujoco.mjtDepthMap.mjDEPTH_ZEROFAR
        extent = model.stat.extent
        self._near = np.float32(model.vis.map.znear * extent)
        self._far = np.float32(model.vis.map.zfar * extent)

    def close(self) -> None:
        """Done with the model's GPU resources (idempotent): freed, unless kept for the next
        model with the same uploads; the process's GL context stays."""
        if self._mjr is not None:
            _release(self._mjr)
        self._mjr = None

    def __enter__(self) -> DepthRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _draw(self, data: mujoco.MjData, camera_id: int, option: mujoco.MjvOption) -> None:
        if self._mjr is None:
            raise RuntimeError("this DepthRenderer is closed; make a new one")
        if not 0 <= camera_id < self.model.ncam:
            raise ValueError(f"camera id {camera_id} outside 0..{self.model.ncam - 1}")
        self._camera.fixedcamid = camera_id
        mujoco.mjv_updateScene(
            self.model, data, option, None, self._camera, mujoco.mjtCatBit.mjCAT_ALL, self._scene
        )
        flags = self._scene.flags.copy()
        # Segment-colour rendering: no lighting or blending, hence exact depth far away too.
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SEGMENT] = True
        self._scene.flags[mujoco.mjtRndFlag.mjRND_IDCOLOR] = True
        gl_context()
        # The buffer binding is the GL context's, shared by every renderer of the process.
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._mjr)
        mujoco.mjr_render(self._rect, self._scene, self._mjr)
        np.copyto(self._scene.flags, flags)

    def depth(
        self, data: mujoco.MjData, camera_id: int, option: mujoco.MjvOption
    ) -> NDArray[np.float32]:
        """(H, W) planar depth in metres of camera ``camera_id`` (``data`` forward-consistent);
        row 0 is the image's top."""
        self._draw(data, camera_id, option)
        z = np.empty((self.height_px, self.width_px), dtype=np.float32)
        mujoco.mjr_readPixels(None, z, self._rect, self._mjr)
        far, near = self._far, self._near
        if self._scene.camera[0].orthographic:
            metric = far - z.astype(np.float64) * (far - near)
        else:
            c = np.float32(-0.5) * (-(far + near) / (far - near)) - np.float32(0.5)
            d = np.float32(-0.5) * (-(np.float32(2) * far * near) / (far - near))
            metric = d / (z.astype(np.float64) + c)
        return np.flipud(metric.astype(np.float32)).copy()

    def segmentation(
        self, data: mujoco.MjData, camera_id: int, option: mujoco.MjvOption
    ) -> NDArray[np.int32]:
        """(H, W, 2) ``(object id, object type)`` of each pixel, ``(-1, -1)`` for background."""
        self._draw(data, camera_id, option)
        rgb = np.empty((self.height_px, self.width_px, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(rgb, None, self._rect, self._mjr)
        seg_id = rgb[..., 0].astype(np.int64) | rgb[..., 1].astype(np.int64) << 8
        seg_id |= rgb[..., 2].astype(np.int64) << 16
        n = self._scene.ngeom
        table = np.full((n + 1, 2), -1, dtype=np.int32)
        for g in self._scene.geoms[:n]:
            if g.segid != -1:
                table[g.segid + 1] = (g.objid, g.objtype)
        return np.flipud(table[seg_id]).copy()
