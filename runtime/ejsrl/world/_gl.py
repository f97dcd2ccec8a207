"""The OpenGL back end of ``ejsrl.world.render``: moderngl on a headless EGL context.

It draws the faces that ``render_triangles`` has already transformed to the camera
frame, culled and shaded (so culling and colours are the NumPy back end's, to the bit):
the GPU (or Mesa's llvmpipe on a machine without one) only rasterizes and depth-tests.

Conventions matched to the NumPy rasterizer: the camera frame is x right, y down, z
forward; pixel (c, r) has its centre at u = c, v = r, so the projection maps u to
``x_ndc = 2 (u + 0.5) / W - 1`` and v to ``y_ndc = 2 (v + 0.5) / H - 1`` (row 0 of the
image is the first row that ``glReadPixels`` returns: no flip); ``w_clip = Z``, and the
fragment shader writes ``gl_FragCoord.w`` = 1/Z, interpolated linearly in screen space as
the NumPy rasterizer does, to a float32 target, from which depth = 1 / (1/Z) (inf where
nothing was drawn). The near and far planes clip as in the NumPy back end. The depth test
runs on Z / far (or Z / (Z + 1 m) without a far plane) written to the depth buffer, rather
than on the usual 1 - near / Z: with far = 100 m it separates surfaces 1e-5 m apart up to
50 m (measured), where 1 - near / Z with near = 1 cm could not separate 1 mm at 10 m. Ties
go to the first face drawn, the lower index, as in the NumPy back end.

Contexts are pooled per process (a forked child makes its own): a render takes a free
context, making one when none is free (up to ``EJSRL_GL_CONTEXTS``, default one per core,
2 to 8), makes it current on the calling thread for the render only, and gives it back.
So the stepper threads of a served class render at the same time, each in its own context
(with one context behind a lock, a session's render waited for another's: bench/classroom.py,
servoing lab), and any thread may render.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["GLUnavailableError", "INSTALL_HINT", "available", "describe", "projection_matrix", "render_faces"]

#: what to install for the "gl" back end
INSTALL_HINT = (
    "pip install moderngl, and the EGL and Mesa libraries "
    "(Debian/Ubuntu: apt-get install libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri)"
)

_VERTEX_SHADER = """
#version 330
uniform mat4 proj;
in vec3 in_pos;
in vec3 in_col;
INTERP out vec3 v_col;
TEX_DECL
void main() {
    v_col = in_col;
TEX_PASS
    gl_Position = proj * vec4(in_pos, 1.0);
}
"""

_FRAGMENT_SHADER = """
#version 330
uniform float inv_far;  // 1 / far, or 0 for no far plane
INTERP in vec3 v_col;
TEX_DECL
layout(location = 0) out vec4 out_rgb;
layout(location = 1) out float out_inv_z;
void main() {
    out_rgb = vec4(v_col, 1.0);
TEX_APPLY
    out_inv_z = gl_FragCoord.w;  // 1 / w_clip = 1 / Z
    // depth-test on Z itself, not on the usual 1 - near / Z, whose steps at a near plane of
    // 1 cm are ~0.1 mm at 2 m and over 1 mm at 10 m
    float z = 1.0 / gl_FragCoord.w;
    gl_FragDepth = inv_far > 0.0 ? z * inv_far : z / (z + 1.0);
}
"""


#: what the shaders get with and without a checker texture (without: the plain shaders, unchanged)
_TEX_SUBS = {
    False: {"v_decl": "", "pass": "", "f_decl": "", "apply": ""},
    True: {
        "v_decl": "in vec3 in_tex;\nsmooth out vec3 v_tex;",
        "pass": "    v_tex = in_tex;",
        "f_decl": "smooth in vec3 v_tex;\nuniform float dark;",
        "apply": "    if (v_tex.z > 0.5 && mod(floor(v_tex.x) + floor(v_tex.y), 2.0) > 0.5) out_rgb.rgb *= dark;",
    },
}


class GLUnavailableError(RuntimeError):
    """The "gl" render back end cannot run here; the message says why and what to install."""


def projection_matrix(K: NDArray[np.float64], width: int, height: int, near: float, far: float) -> NDArray[np.float64]:
    """The (4, 4) OpenGL projection of a pinhole camera, camera frame (x right, y down, z forward) -> clip.

    ``K`` (3, 3): intrinsics with pixel centres at integer coordinates. ``x_ndc = 2 (u + 0.5) / W - 1``,
    ``y_ndc = 2 (v + 0.5) / H - 1``, ``w_clip = Z``; ``z_ndc`` goes from -1 at ``near`` to +1 at
    ``far`` (``far`` may be inf).
    """
    W, H = float(width), float(height)
    fx, s, cx = K[0, 0], K[0, 1], K[0, 2]
    fy, cy = K[1, 1], K[1, 2]
    if np.isfinite(far):
        a, b = (far + near) / (far - near), -2.0 * far * near / (far - near)
    else:
        a, b = 1.0, -2.0 * near
    return np.array(
        [
            [2.0 * fx / W, 2.0 * s / W, 2.0 * (cx + 0.5) / W - 1.0, 0.0],
            [0.0, 2.0 * fy / H, 2.0 * (cy + 0.5) / H - 1.0, 0.0],
            [0.0, 0.0, a, b],
            [0.0, 0.0, 1.0, 0.0],
        ]
    )


class _Renderer:
    """The context, program and buffers, reused from frame to frame."""

    def __init__(self) -> None:
        import moderngl

        self.mgl = moderngl
        self.ctx = moderngl.create_context(standalone=True, backend="egl", require=330)  # current on this thread
        try:
            self._setup()
        finally:
            _release_current()  # free for whichever thread the pool lends it to

    def _setup(self) -> None:
        """Buffers, programs and vertex arrays, made with the new context current."""
        self.vbo = self.ctx.buffer(reserve=36 * 64, dynamic=True)
        self.cbo = self.ctx.buffer(reserve=9 * 64, dynamic=True)
        self.tbo = self.ctx.buffer(reserve=36 * 64, dynamic=True)
        # flat: one colour per face; smooth: per-corner colours interpolated (perspective-correct);
        # "+tex": a checker texture from per-corner coordinates (s, t, on) interpolated likewise
        self.progs = {}
        self.vaos = {}
        for qualifier in ("flat", "smooth"):
            for tex in (False, True):
                subs = _TEX_SUBS[tex]
                vs, fs = _VERTEX_SHADER.replace("INTERP", qualifier), _FRAGMENT_SHADER.replace("INTERP", qualifier)
                vs = vs.replace("TEX_DECL", subs["v_decl"]).replace("TEX_PASS", subs["pass"])
                fs = fs.replace("TEX_DECL", subs["f_decl"]).replace("TEX_APPLY", subs["apply"])
                mode = qualifier + ("+tex" if tex else "")
                prog = self.progs[mode] = self.ctx.program(vertex_shader=vs, fragment_shader=fs)
                attrs = [(self.vbo, "3f", "in_pos"), (self.cbo, "3f1", "in_col")] + ([(self.tbo, "3f", "in_tex")] if tex else [])
                self.vaos[mode] = self.ctx.vertex_array(prog, attrs)
        self.targets: dict[tuple[int, int], tuple[Any, Any, Any]] = {}
        self.finish = _gil_free_finish()
        self.clear = _gil_free_clear()
        info = self.ctx.info
        self.renderer = f"{info.get('GL_RENDERER', '?')} ({info.get('GL_VERSION', '?')})"

    def _target(self, W: int, H: int) -> tuple[Any, Any, Any]:
        """(draw framebuffer, colour-only framebuffer, 1/Z-and-depth framebuffer) of size W x H."""
        fbs = self.targets.get((W, H))
        if fbs is None:
            ctx = self.ctx
            rgb = ctx.texture((W, H), 4, dtype="f1")
            inv_z = ctx.texture((W, H), 1, dtype="f4")
            depth = ctx.depth_renderbuffer((W, H))
            draw = ctx.framebuffer(color_attachments=[rgb, inv_z], depth_attachment=depth)
            fbs = (draw, ctx.framebuffer(color_attachments=[rgb]), ctx.framebuffer(color_attachments=[inv_z], depth_attachment=depth))
            if len(self.targets) >= 8:  # keep a few sizes, drop the oldest
                for obj in self.targets.pop(next(iter(self.targets))):
                    obj.release()
            self.targets[(W, H)] = fbs
        return fbs

    def render(
        self, P: NDArray[np.float64], shaded: NDArray[np.uint8], camera: Any, bg: NDArray[np.uint8],
        tex: NDArray[np.float64] | None = None, dark: float = 1.0,
    ) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
        W, H = int(camera.width), int(camera.height)
        F = P.shape[2]
        pos = np.ascontiguousarray(P.transpose(2, 0, 1), dtype=np.float32)  # (F, 3 vertices, 3)
        mode = "smooth" if shaded.ndim == 3 else "flat"
        if mode == "smooth":  # (F, 3 corners, 3)
            col = np.ascontiguousarray(shaded, dtype=np.uint8).reshape(-1, 3)
        else:
            col = np.repeat(shaded, 3, axis=0)  # one colour per vertex, the face's
        bufs = [(self.vbo, pos), (self.cbo, col)]
        if tex is not None:
            mode += "+tex"
            bufs.append((self.tbo, np.ascontiguousarray(tex, dtype=np.float32).reshape(-1, 3)))
        prog, vao = self.progs[mode], self.vaos[mode]
        proj = projection_matrix(camera.K, W, H, camera.near, camera.far)
        rgba = np.empty((H, W, 4), dtype=np.uint8)  # RGBA reads are a copy; RGB ones convert each pixel (7x slower)
        inv_z = np.empty((H, W), dtype=np.float32)
        with self.ctx:  # one thread at a time: the pool lends it to one
            draw, colour_only, inv_z_depth = self._target(W, H)
            if F:
                for buf, data in bufs:
                    if buf.size < data.nbytes:
                        buf.orphan(data.nbytes + data.nbytes // 4)
                    buf.write(data)
            prog["proj"].write(proj.T.astype(np.float32).tobytes())  # GL wants column-major
            prog["inv_far"].value = 1.0 / camera.far if np.isfinite(camera.far) else 0.0
            if tex is not None:
                prog["dark"].value = float(dark)
            self.clear(colour_only, (*(float(c) / 255.0 for c in bg[:3]), 1.0))
            self.clear(inv_z_depth, (0.0, 0.0, 0.0, 0.0), depth=1.0)
            draw.use()
            self.ctx.enable_only(self.mgl.DEPTH_TEST)
            self.ctx.depth_func = "<"
            if F:
                vao.render(self.mgl.TRIANGLES, vertices=3 * F)
            self.finish()  # the rasterising, without the GIL (see _gil_free_finish)
            draw.read_into(rgba, components=4, attachment=0, alignment=1)
            draw.read_into(inv_z, components=1, attachment=1, alignment=1, dtype="f4")
        with np.errstate(divide="ignore"):
            depth = np.divide(np.float32(1.0), inv_z, out=inv_z)  # 1 / 0 = inf where empty
        return np.ascontiguousarray(rgba[..., :3]), depth


def _gil_free_finish() -> Callable[[], None]:
    """``glFinish`` called through ctypes, which lets go of the GIL while it waits.

    moderngl keeps the GIL in every call, and with Mesa's llvmpipe the rasterising happens
    in the wait for the pixels: a served class's other sessions could not run meanwhile
    (bench/classroom.py, six-axis lab: a third of the server's GIL time was that wait).
    Called before the read, it leaves the read a copy. Through GLVND's libGL it reaches the
    context current on this thread; without the library it does nothing (the read waits).
    """
    import ctypes
    import ctypes.util

    for name in ("libGL.so.1", "libOpenGL.so.0", ctypes.util.find_library("GL")):
        if not name:
            continue
        try:
            fn = ctypes.CDLL(name).glFinish
        except (OSError, AttributeError):
            continue
        fn.restype = None
        fn.argtypes = []
        return fn
    return lambda: None


def _gil_free_clear() -> Callable[..., None]:
    """``clear(framebuffer, rgba, depth=None)``: what moderngl's ``framebuffer.clear`` does, with
    ``glClearColor``/``glClearDepth``/``glClear`` called through ctypes, which lets go of the GIL.

    With Mesa's llvmpipe a clear writes every pixel while the call runs: through moderngl
    (which keeps the GIL) the two clears of a capture held it 0.73-1.13 ms for 0.03-0.06 ms of
    this thread's CPU, and a served class's other sessions waited (bench/classroom.py, six-axis
    and servoing labs). ``framebuffer.use()`` (moderngl) binds the framebuffer with its viewport,
    draw buffers and write masks first, as its ``clear`` does. Without the GL library the
    framebuffer's own ``clear`` runs.
    """
    import ctypes
    import ctypes.util

    lib = None
    for name in ("libGL.so.1", "libOpenGL.so.0", ctypes.util.find_library("GL")):
        if not name:
            continue
        try:
            lib = ctypes.CDLL(name)
            gl_clear, clear_color, clear_depth = lib.glClear, lib.glClearColor, lib.glClearDepth
            break
        except (OSError, AttributeError):
            lib = None
    if lib is None:
        def fallback(fb: Any, rgba: tuple[float, float, float, float], depth: float | None = None) -> None:
            fb.clear(*rgba, depth=1.0 if depth is None else depth)
        return fallback
    gl_clear.argtypes, gl_clear.restype = [ctypes.c_uint], None
    clear_color.argtypes, clear_color.restype = [ctypes.c_float] * 4, None
    clear_depth.argtypes, clear_depth.restype = [ctypes.c_double], None
    colour_bit, depth_bit = 0x4000, 0x100  # GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT

    def clear(fb: Any, rgba: tuple[float, float, float, float], depth: float | None = None) -> None:
        fb.use()
        clear_color(*rgba)
        if depth is None:
            gl_clear(colour_bit)
        else:
            clear_depth(depth)
            gl_clear(colour_bit | depth_bit)
    return clear


def _release_current() -> None:
    """Make no context current on this thread (moderngl leaves a new context current on the
    thread that made it, where no other thread could make it current; ``with ctx:`` later
    restores what was current before, so each render leaves the thread with none)."""
    import ctypes

    try:
        egl = ctypes.CDLL("libEGL.so.1")
    except OSError:
        return
    egl.eglGetCurrentDisplay.restype = ctypes.c_void_p
    egl.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
    egl.eglMakeCurrent.restype = ctypes.c_uint
    display = egl.eglGetCurrentDisplay()
    if display:
        egl.eglMakeCurrent(display, None, None, None)


def context_limit() -> int:
    """How many contexts a process makes at most: ``EJSRL_GL_CONTEXTS``, else one per core
    (Mesa's llvmpipe rasterises on every core already; more contexts than that only wait)."""
    forced = os.environ.get("EJSRL_GL_CONTEXTS", "").strip()
    if forced.isdigit() and int(forced) > 0:
        return int(forced)
    return max(2, min(8, os.cpu_count() or 1))


class _Pool:
    """The process's renderers: each lent to one thread at a time, made when all are lent."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self.pid = os.getpid()
        self.free: list[_Renderer] = []
        self.made = 0
        self.failure: str | None = None
        self.cv = threading.Condition()

    def _take(self) -> _Renderer:
        with self.cv:
            while True:
                if self.free:
                    return self.free.pop()
                if self.made == 0 and self.failure is not None:
                    raise GLUnavailableError(
                        f"the 'gl' render backend is not available: {self.failure}. To use it: {INSTALL_HINT}"
                    )
                if self.made < self.limit:
                    self.made += 1
                    break
                self.cv.wait()
        try:  # outside the lock: compiling the shaders takes a while, others may render meanwhile
            return _Renderer()
        except Exception as exc:
            with self.cv:
                self.made -= 1
                if self.made == 0:  # none could be made: the back end is unavailable here
                    self.failure = (
                        f"moderngl is not installed ({exc})" if isinstance(exc, ImportError)
                        else f"no OpenGL context through EGL: {type(exc).__name__}: {exc}".strip()
                    )
                else:  # out of contexts (memory, driver): share the ones there are
                    self.limit = self.made
                self.cv.notify_all()
            return self._take()

    @contextlib.contextmanager
    def renderer(self) -> Iterator[_Renderer]:
        """A renderer for this thread alone until the block ends; raises GLUnavailableError
        (every time) when no context can be made in this process."""
        r = self._take()
        try:
            yield r
        finally:
            with self.cv:
                self.free.append(r)
                self.cv.notify()

    def size(self) -> int:
        """How many contexts exist."""
        with self.cv:
            return self.made


_lock = threading.Lock()
_the_pool: _Pool | None = None


def _pool() -> _Pool:
    """This process's pool (a forked child gets a new one: the parent's contexts are not its to use)."""
    global _the_pool
    with _lock:
        if _the_pool is None or _the_pool.pid != os.getpid():
            _the_pool = _Pool(context_limit())
        return _the_pool


def _get() -> _Renderer:
    """A renderer, given back at once (for what every context shares: availability, its name)."""
    with _pool().renderer() as r:
        return r


def available() -> bool:
    """True when moderngl imports and a headless EGL context could be made (tried once, then cached)."""
    try:
        _get()
    except GLUnavailableError:
        return False
    return True


def describe() -> str:
    """The OpenGL renderer in use ("llvmpipe ..." for Mesa's CPU driver), or why there is none."""
    try:
        return _get().renderer
    except GLUnavailableError as exc:
        return str(exc)


def render_faces(
    P: NDArray[np.float64], shaded: NDArray[np.uint8], camera: Any, bg: NDArray[np.uint8],
    tex: NDArray[np.float64] | None = None, dark: float = 1.0,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Draw camera-frame faces ``P`` (3, 3, F) (vertex-major) with flat colours ``shaded`` (F, 3) uint8,
    or per-corner colours (F, 3 corners, 3) uint8 interpolated across each face (smooth shading).

    ``tex`` (F, 3 corners, 3): checker coordinates (s, t) in squares and 1 on textured faces
    (0 elsewhere); where floor(s) + floor(t) is odd the colour is multiplied by ``dark``.
    ``camera``: a ``CameraModel`` (K, width, height, near, far). ``bg`` (3,) uint8. Returns
    ``rgb`` (H, W, 3) uint8 and ``depth`` (H, W) float32, Z in metres, inf where empty.
    """
    with _pool().renderer() as r:
        return r.render(P, shaded, camera, bg, tex, dark)
