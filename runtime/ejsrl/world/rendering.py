"""Virtual-camera rendering of the world: RGB and depth images from a camera pose.

``render(world, "cam")`` is what ``capture("cam")`` returns in apps, with or without a
browser. Two back ends draw the same picture:

- ``"numpy"``: the z-buffer rasterizer of ``_raster.py``, deterministic, always there;
- ``"gl"``: OpenGL through moderngl on a headless EGL context (``_gl.py``): Mesa's
  llvmpipe on a machine without a GPU, the GPU's driver where there is one. It needs
  ``pip install moderngl`` and the EGL and Mesa libraries (Debian: ``libegl1 libgl1
  libegl-mesa0 libgl1-mesa-dri``). It agrees with the NumPy one except for pixels on
  triangle edges (its fill rule differs) and for depth rounding (float32 on the GPU;
  its depth test separates surfaces about 1e-5 m apart, the NumPy one ~1e-7 relative).

``backend="auto"`` (the default) picks ``"gl"`` when moderngl imports and an EGL context
can be made (tried once per process, then cached), else ``"numpy"``; the
environment variable ``EJSRL_RENDER_BACKEND`` (``numpy``, ``gl`` or ``auto``) overrides
what "auto" means, for example to get the NumPy output everywhere.

Shading, the same on both back ends (computed here, on the CPU, in float64): each face
gets its colour times ``ambient + (1 - ambient) * |cos a|`` where ``a`` is the angle
between its normal and ``LIGHT_DIR``, a light attached to the camera (so faces seen
edge-on are darker); no textures, no shadows.

A more realistic camera (``realism=``, or a camera node's ``antialias``, ``shading``,
``noise``, ``blur`` and ``distortion`` properties; all off by default, and then the render
is the plain one, bit for bit): supersampling, smooth (Gouraud) shading, lens distortion
through the camera's own ``CameraModel.distort``, defocus blur and Gaussian sensor noise,
on both back ends (see ``ejsrl.world._realism``). A solid node whose ``texture`` is
``"checker"`` shows a checkerboard of ``texture_size`` squares in its own frame (see
``texture_coords``). A solid node whose ``texture`` is ``"<dictionary>:<id>"`` (say
``"aruco_4x4_50:7"``, ``"apriltag_36h11:0"``; see ``ejsrl.vision.markers``) shows that fiducial
marker, ``texture_size`` metres a side, centred on its origin, on its faces that look along
its +z axis (see ``marker_coords``): the NumPy back end paints it per pixel, the GL back end
draws its black cells as decal faces (``ejsrl.world._marker_decals``): the same pixels but on
the cells' edges.
``render_depth`` is the depth image alone.
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision.camera import CameraModel
from ejsrl.world._raster import face_normals, front_faces, zbuffer
from ejsrl.world._realism import Realism, block_mean, centre_depth, corner_normals, margin_for, supersampled_K

__all__ = [
    "render", "render_depth", "render_triangles", "shade_faces", "available_backends", "Realism",
    "BACKGROUND", "AMBIENT", "BACKENDS",
]

#: default background colour, RGB in [0, 1] (a light grey-blue)
BACKGROUND: tuple[float, float, float] = (0.82, 0.86, 0.92)
#: share of a face's colour it keeps when seen edge-on
AMBIENT: float = 0.3
#: unit vector towards the light in the camera frame (x right, y down, z forward)
LIGHT_DIR: NDArray[np.float64] = np.array([-0.25, -0.35, -1.0]) / np.linalg.norm([-0.25, -0.35, -1.0])
#: the values ``backend`` takes
BACKENDS: tuple[str, ...] = ("auto", "numpy", "gl")
#: the textures a solid element may have (its ``texture`` property), as the virtual camera sees them
TEXTURES: tuple[str, ...] = ("checker",)
#: the side of a checker's squares (metres) when a node gives no ``texture_size``
DEFAULT_TEXTURE_SIZE: float = 0.05
#: the dark squares of a checker texture: the face's colour times this
CHECKER_DARK: float = 0.4
#: the black cells of a marker texture: the face's colour times this (printed black is not quite black)
MARKER_DARK: float = 0.08


def _shade(n: NDArray[np.float64], rgb: NDArray[np.float64], ambient: float) -> NDArray[np.uint8]:
    """Flat shading from camera-frame face normals ``n`` (3, F) and colours (F, 3) -> (F, 3) uint8."""
    nn = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(n[0] * LIGHT_DIR[0] + n[1] * LIGHT_DIR[1] + n[2] * LIGHT_DIR[2]) / nn
    cos = np.nan_to_num(cos, nan=1.0)
    k = ambient + (1.0 - ambient) * cos
    return np.clip(np.rint(255.0 * np.clip(rgb, 0.0, 1.0) * k[:, None]), 0, 255).astype(np.uint8)


def _shade_corners(cn: NDArray[np.float64], rgb: NDArray[np.float64], ambient: float) -> NDArray[np.uint8]:
    """Gouraud shading: unit corner normals ``cn`` (3 corners, 3, F), colours (F, 3) -> (F, 3 corners, 3) uint8."""
    cos = np.abs(np.einsum("vcf,c->fv", cn, LIGHT_DIR))
    k = ambient + (1.0 - ambient) * cos  # (F, 3 corners)
    return np.clip(np.rint(255.0 * np.clip(rgb, 0.0, 1.0)[:, None, :] * k[:, :, None]), 0, 255).astype(np.uint8)


def shade_faces(
    tris_cam: NDArray[np.float64], rgb: NDArray[np.float64], ambient: float = AMBIENT
) -> NDArray[np.uint8]:
    """Flat shading: camera-frame triangles (F, 3, 3) and colours (F, 3) in [0, 1] -> (F, 3) uint8.

    The light comes from the camera, slightly from its upper left (``LIGHT_DIR``, camera
    frame), so coplanar faces get the same shade and the sides of a box differ.
    """
    tris_cam = np.asarray(tris_cam, dtype=np.float64).reshape(-1, 3, 3)
    P = np.ascontiguousarray(tris_cam.transpose(1, 2, 0))
    return _shade(face_normals(P), np.asarray(rgb, dtype=np.float64).reshape(-1, 3), ambient)


def _bg_uint8(background: Sequence[float]) -> NDArray[np.uint8]:
    bg = np.asarray(background, dtype=np.float64).reshape(3)
    if bg.max() > 1.0:  # allow 0-255 too
        bg = bg / 255.0
    return np.clip(np.rint(bg * 255.0), 0, 255).astype(np.uint8)


def _to_camera(tris_world: NDArray[np.float64], T_world_camera: NDArray[np.float64]) -> NDArray[np.float64]:
    """World triangles (F, 3, 3) -> camera-frame triangles laid out (3, 3, F): ``P[v, c]``, coordinate c of vertex v."""
    R, t = T_world_camera[:3, :3], T_world_camera[:3, 3]
    Q = tris_world.transpose(1, 2, 0) - t[None, :, None]  # (3 vertices, 3 coordinates, F)
    return np.matmul(R.T, Q)  # R^T (p - t) for every vertex


def available_backends() -> list[str]:
    """The back ends that work in this process: always "numpy", and "gl" when moderngl and EGL do."""
    from ejsrl.world import _gl

    return ["numpy"] + (["gl"] if _gl.available() else [])


def _pick_backend(backend: str) -> str:
    """The back end that ``backend`` resolves to: "numpy" or "gl" (see the module docstring)."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown render backend {backend!r}; choose one of {', '.join(map(repr, BACKENDS))}")
    if backend == "auto":
        backend = os.environ.get("EJSRL_RENDER_BACKEND", "auto").strip().lower() or "auto"
        if backend not in BACKENDS:
            raise ValueError(
                f"EJSRL_RENDER_BACKEND={backend!r} is not a render backend; use one of {', '.join(map(repr, BACKENDS))}"
            )
        if backend == "auto":
            from ejsrl.world import _gl

            return "gl" if _gl.available() else "numpy"
    return backend


def render_triangles(
    tris_world: ArrayLike,
    rgb: ArrayLike,
    camera: CameraModel,
    T_world_camera: ArrayLike,
    *,
    background: Sequence[float] = BACKGROUND,
    cull_backfaces: bool = True,
    backend: str = "numpy",
    realism: Realism | None = None,
    rng: np.random.Generator | None = None,
    texture: NDArray[np.float64] | None = None,
    markers: tuple[NDArray[np.float64], list[NDArray[np.bool_]]] | None = None,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render world triangles (F, 3, 3) with colours (F, 3) in [0, 1] seen by ``camera``.

    ``T_world_camera``: (4, 4) pose of the camera in the world. ``backend``: "numpy", "gl"
    or "auto" (see the module docstring). ``realism``: anti-aliasing, smooth shading, lens
    distortion, blur and noise (``Realism``; None or all off: the plain pinhole render);
    ``rng``: the generator of the noise (default: a fresh one). ``texture`` (F, 3 corners,
    3): checker coordinates (s, t), in squares, and 1 on textured faces, 0 elsewhere (see
    ``texture_coords``); the dark squares are ``CHECKER_DARK`` times as bright. ``markers``:
    what ``marker_coords`` gives (the GL back end draws their black cells as decal faces:
    ``ejsrl.world._marker_decals``). Returns ``rgb`` (H, W, 3)
    uint8 and ``depth`` (H, W) float32 (metres along the optical axis, inf where nothing is seen).
    """
    be = _pick_backend(backend)
    tris = np.asarray(tris_world, dtype=np.float64).reshape(-1, 3, 3)
    cols = np.asarray(rgb, dtype=np.float64).reshape(-1, 3)
    T = np.asarray(T_world_camera, dtype=np.float64)
    bg = _bg_uint8(background)
    P = _to_camera(tris, T)
    n = face_normals(P)
    front = front_faces(P, n) if cull_backfaces else None
    if texture is not None and not np.any(np.asarray(texture)[:, :, 2] > 0.5):
        texture = None
    if markers is not None and not np.any(markers[0][:, 0, 2] > 0.5):
        markers = None
    if texture is not None or markers is not None or (realism is not None and not realism.plain):
        realism = realism or Realism()
        cn = _world_corner_normals(tris, T[:3, :3]) if realism.shading == "smooth" else None
        tex = None if texture is None else np.asarray(texture, dtype=np.float64).reshape(-1, 3, 3)
        return _render_realistic(P, n, cols, front, camera, bg, be, realism, rng, cn, tex, markers)
    if be == "gl":
        from ejsrl.world import _gl

        keep = np.flatnonzero(front) if front is not None else np.arange(P.shape[2])
        shaded = _shade(n.take(keep, axis=1), cols[keep], AMBIENT)
        return _gl.render_faces(P.take(keep, axis=2), shaded, camera, bg)
    zb = zbuffer(P, camera.K, camera.width, camera.height, near=camera.near, far=camera.far, front=front)
    shaded = _shade(n.take(zb.ids, axis=1), cols[zb.ids], AMBIENT)  # only the faces drawn
    return zb.lookup(shaded, bg), zb.depth()


_CN_CACHE: dict[bytes, NDArray[np.float64]] = {}
_CN_LOCK = threading.Lock()


def _world_corner_normals(tris: NDArray[np.float64], R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Smooth-shading corner normals (3, 3, F) in the camera frame (rotation ``R`` of the camera in the world).

    Computed in the world frame and kept for the last few triangle sets, so a still scene
    seen by a moving camera computes them once.
    """
    import hashlib

    key = hashlib.blake2b(np.ascontiguousarray(tris).tobytes(), digest_size=16).digest()
    with _CN_LOCK:
        cnw = _CN_CACHE.pop(key, None)
    if cnw is None:
        Pw = np.ascontiguousarray(tris.transpose(1, 2, 0))
        cnw = corner_normals(Pw, face_normals(Pw))
    with _CN_LOCK:  # renders may run on several threads
        _CN_CACHE[key] = cnw
        while len(_CN_CACHE) > 4:
            del _CN_CACHE[next(iter(_CN_CACHE))]
    return np.einsum("ij,vif->vjf", R, cnw)  # R^T n for every corner


def texture_coords(world: Any, exclude: Sequence[str], tris: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Checker coordinates (F, 3 corners, 3) of ``world.triangles(exclude)`` = ``tris``; None if none is textured.

    A textured node's face gets, at each corner, its coordinates in the node's frame along the
    two axes most across the face, divided by the node's ``texture_size``, and a third
    number 1 (0 on untextured faces). So a box face shows whole squares from its centre
    lines, and the squares stay on the object as it moves.
    """
    skip = set(exclude)
    entries: list[tuple[int, Any, float]] = []
    textured = False
    for node in world.walk():  # the walk of World.triangles
        if node.name in skip or not world.is_visible(node) or node.opacity <= 0.0:
            continue
        parts = node.parts()
        if not parts:
            continue
        count = sum(len(p.faces) for p in parts)
        tex = node.props.get("texture")
        if tex in (None, "", "none") or _marker_of(node) is not None:
            entries.append((count, None, 0.0))
            continue
        if tex not in TEXTURES:
            raise ValueError(
                f"'{node.name}': texture {tex!r} is not one of {', '.join(map(repr, TEXTURES))} (or a marker "
                "'<dictionary>:<id>' such as 'aruco_4x4_50:7', or leave it out)"
            )
        raw = node.props.get("texture_size")
        size = DEFAULT_TEXTURE_SIZE if raw is None else float(raw)
        if not (math.isfinite(size) and size > 0):
            raise ValueError(f"'{node.name}': texture_size must be a length > 0 in metres, got {node.props.get('texture_size')!r}")
        entries.append((count, node.T_world(), size))
        textured = True
    if not textured or sum(c for c, _, _ in entries) != len(tris):
        return None
    out = np.zeros((len(tris), 3, 3))
    i = 0
    axes = np.array([[1, 2], [0, 2], [0, 1]])
    for count, T, size in entries:
        if T is not None:
            local = (tris[i : i + count] - T[:3, 3]) @ T[:3, :3]  # (count, 3 corners, 3) in the node frame
            nrm = np.cross(local[:, 1] - local[:, 0], local[:, 2] - local[:, 0])
            keep = axes[np.argmax(np.abs(nrm), axis=1)]  # (count, 2): the two axes across the face
            out[i : i + count, :, :2] = np.take_along_axis(local, keep[:, None, :], axis=2) / size
            out[i : i + count, :, 2] = 1.0
        i += count
    return out


def texture_problem(texture: Any) -> tuple[str, str] | None:
    """``(message, hint)`` when a constant ``texture`` value cannot be drawn (for build errors), else None."""
    if not isinstance(texture, str) or texture in ("", "none") or texture in TEXTURES:
        return None
    if ":" in texture:
        from ejsrl.vision.markers import parse_marker_texture

        try:
            if parse_marker_texture(texture) is not None:
                return None
        except ValueError as e:
            msg = str(e)
            if "did you mean" in msg:
                hint = msg.split("; ", 1)[1].split(" (use", 1)[0]
            elif "is not in" in msg:
                hint = "pick an id in that range, or a dictionary with more markers (aruco_4x4_1000, apriltag_36h11)"
            else:
                hint = "e.g. texture: 'aruco_4x4_50:7'"
            return msg.split("; did you mean")[0], hint
    return (f"texture '{texture}' is not one of {', '.join(map(repr, TEXTURES))} or a marker '<dictionary>:<id>'",
            "e.g. texture: checker, or texture: 'aruco_4x4_50:7'")


def _marker_of(node: Any) -> tuple[str, int] | None:
    """(dictionary, id) of a node's marker texture, None if it has none (ValueError if it is malformed)."""
    tex = node.props.get("texture")
    if not isinstance(tex, str) or ":" not in tex:
        return None
    from ejsrl.vision.markers import parse_marker_texture

    try:
        return parse_marker_texture(tex)
    except ValueError as e:
        raise ValueError(f"'{node.name}': {e}") from None


def marker_coords(
    world: Any, exclude: Sequence[str], tris: NDArray[np.float64]
) -> tuple[NDArray[np.float64], list[NDArray[np.bool_]]] | None:
    """Marker coordinates of ``world.triangles(exclude)`` = ``tris``; None if no node has a marker texture.

    Returns ``(coords, bitmaps)``: ``coords`` (F, 3 corners, 3) holds, on the faces of a
    marker node that look along its +z axis, the corner's (u, v) = (x, y) / side + 1/2 in the
    node's frame (the marker fills 0 <= u, v < 1) and k + 1, where ``bitmaps[k]`` (n + 2,
    n + 2) bool (True = black, row 0 at the top, i.e. +y) is that node's marker; 0 elsewhere.
    """
    skip = set(exclude)
    entries: list[tuple[int, Any, float, int]] = []
    bitmaps: list[NDArray[np.bool_]] = []
    for node in world.walk():  # the walk of World.triangles
        if node.name in skip or not world.is_visible(node) or node.opacity <= 0.0:
            continue
        parts = node.parts()
        if not parts:
            continue
        count = sum(len(p.faces) for p in parts)
        mk = _marker_of(node)
        if mk is None:
            entries.append((count, None, 0.0, -1))
            continue
        from ejsrl.vision.markers import marker_bits

        raw = node.props.get("texture_size")
        side = DEFAULT_TEXTURE_SIZE if raw is None else float(raw)
        if not (math.isfinite(side) and side > 0):
            raise ValueError(f"'{node.name}': texture_size is the marker's side, a length > 0 in metres, got {raw!r}")
        bitmaps.append(marker_bits(*mk))
        entries.append((count, node.T_world(), side, len(bitmaps) - 1))
    if not bitmaps or sum(e[0] for e in entries) != len(tris):
        return None
    out = np.zeros((len(tris), 3, 3))
    i = 0
    for count, T, side, k in entries:
        if T is not None:
            local = (tris[i : i + count] - T[:3, 3]) @ T[:3, :3]  # (count, 3 corners, 3) in the node frame
            nrm = np.cross(local[:, 1] - local[:, 0], local[:, 2] - local[:, 0])
            up = (nrm[:, 2] > 0) & (np.abs(nrm[:, 2]) >= np.abs(nrm[:, :2]).max(axis=1))
            out[i : i + count, :, :2] = np.where(up[:, None, None], local[:, :, :2] / side + 0.5, 0.0)
            out[i : i + count, :, 2] = np.where(up, float(k + 1), 0.0)[:, None]
        i += count
    return out, bitmaps


def _paint_markers(
    col: NDArray[np.float64], f: NDArray[np.int64], b: NDArray[np.float64],
    markers: tuple[NDArray[np.float64], list[NDArray[np.bool_]]],
) -> None:
    """Darken, in place, the pixels (colours ``col`` (N, 3) of faces ``f`` at barycentrics ``b``) on black marker cells."""
    coords, bitmaps = markers
    t = coords[f]  # (N, 3 corners, 3)
    k = np.rint(t[:, 0, 2]).astype(np.int64) - 1
    on = np.flatnonzero(k >= 0)
    if not len(on):
        return
    uv = np.einsum("nv,nvc->nc", b[on], t[on, :, :2])
    for j, bits in enumerate(bitmaps):
        sel = k[on] == j
        if not sel.any():
            continue
        u, v = uv[sel, 0], uv[sel, 1]
        inside = (u >= 0) & (u < 1) & (v >= 0) & (v < 1)
        cells = bits.shape[0]
        c = np.clip(np.floor(u * cells).astype(np.int64), 0, cells - 1)
        r = np.clip(np.floor((1.0 - v) * cells).astype(np.int64), 0, cells - 1)
        dark = inside & bits[r, c]
        col[on[sel][dark]] *= MARKER_DARK


def _barycentric_planes(P: NDArray[np.float64], n: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per face (12, F): n (3), d = n.V0, then c0, g0 (3), c1, g1 (3) of ``_render_per_pixel_numpy``."""
    V0, V1, V2 = P[0], P[1], P[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_n2 = 1.0 / np.einsum("cf,cf->f", n, n)
    g0 = np.cross(V1 - V2, n, axis=0) * inv_n2
    g1 = np.cross(V2 - V0, n, axis=0) * inv_n2
    c0 = np.einsum("cf,cf->f", n, np.cross(V1, V2, axis=0)) * inv_n2
    c1 = np.einsum("cf,cf->f", n, np.cross(V2, V0, axis=0)) * inv_n2
    d = np.einsum("cf,cf->f", n, V0)
    return np.vstack([n, d[None], c0[None], g0, c1[None], g1])


def _render_per_pixel_numpy(
    P: NDArray[np.float64], n: NDArray[np.float64], cols: NDArray[np.float64], front: NDArray[np.bool_] | None,
    camera: CameraModel, bg: NDArray[np.uint8], cn: NDArray[np.float64] | None, tex: NDArray[np.float64] | None,
    markers: tuple[NDArray[np.float64], list[NDArray[np.bool_]]] | None = None,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """NumPy render with per-pixel colours: Gouraud shading (corner colours interpolated with
    perspective-correct barycentrics) when ``cn`` is given, else flat; a checker where ``tex``
    says, a marker where ``markers`` says."""
    W, H = camera.width, camera.height
    zb = zbuffer(P, camera.K, W, H, near=camera.near, far=camera.far, front=front)
    depth = zb.depth()
    face = zb.face().reshape(-1)
    out = np.empty((H * W, 3), dtype=np.uint8)
    out[:] = bg
    pix = np.flatnonzero(face >= 0)
    if len(pix):
        f = face[pix]
        K = camera.K
        v = (pix // W).astype(np.float64)
        u = (pix % W).astype(np.float64)
        yn = (v - K[1, 2]) / K[1, 1]
        xn = (u - K[0, 2] - K[0, 1] * yn) / K[0, 0]
        # Per face: the ray r = (xn, yn, 1) meets the face's plane n.X = d at X = r d / (n.r), where
        # its barycentrics are b0 = c0 + g0.X and b1 = c1 + g1.X, with
        # c0 = n.(V1 x V2) / |n|^2, g0 = (V1 - V2) x n / |n|^2 (and V2, V0 for b1).
        tab = _barycentric_planes(P, n).take(f, axis=1)  # (12, N)
        with np.errstate(divide="ignore", invalid="ignore"):
            scale = tab[3] / (tab[0] * xn + tab[1] * yn + tab[2])
            b0 = tab[4] + scale * (tab[5] * xn + tab[6] * yn + tab[7])
            b1 = tab[8] + scale * (tab[9] * xn + tab[10] * yn + tab[11])
        b0, b1 = np.nan_to_num(b0, nan=1 / 3), np.nan_to_num(b1, nan=1 / 3)
        b = np.clip(np.stack([b0, b1, 1.0 - b0 - b1], axis=1), 0.0, 1.0)
        b /= b.sum(axis=1, keepdims=True)
        if cn is not None:
            corner = _shade_corners(cn, cols, AMBIENT)[f].astype(np.float64)  # (N, 3 corners, 3)
            col = np.einsum("nv,nvc->nc", b, corner)
        else:
            col = _shade(n, cols, AMBIENT)[f].astype(np.float64)
        if tex is not None:
            t = tex[f]  # (N, 3 corners, 3)
            st = np.einsum("nv,nvc->nc", b, t[:, :, :2])
            odd = (t[:, 0, 2] > 0.5) & (np.mod(np.floor(st[:, 0]) + np.floor(st[:, 1]), 2.0) > 0.5)
            col[odd] *= np.float32(CHECKER_DARK)  # the GL shader multiplies in float32
        if markers is not None:
            _paint_markers(col, f, b, markers)
        out[pix] = np.clip(np.rint(col), 0, 255).astype(np.uint8)
    return out.reshape(H, W, 3), depth


def _render_pinhole(
    P: NDArray[np.float64], n: NDArray[np.float64], cols: NDArray[np.float64], front: NDArray[np.bool_] | None,
    camera: CameraModel, bg: NDArray[np.uint8], be: str, cn: NDArray[np.float64] | None,
    tex: NDArray[np.float64] | None = None,
    markers: tuple[NDArray[np.float64], list[NDArray[np.bool_]]] | None = None,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """The pinhole render of camera-frame faces on back end ``be``: flat, or smooth with corner
    normals ``cn``; a checker texture where ``tex`` says; markers where ``markers`` says (on
    GL as decal faces: ``ejsrl.world._marker_decals``)."""
    smooth = cn is not None
    if be == "gl":
        from ejsrl.world import _gl

        keep = np.flatnonzero(front) if front is not None else np.arange(P.shape[2])
        if markers is not None:
            from ejsrl.world._marker_decals import marker_decals

            Pd, nd, cd, src, bary = marker_decals(P, n, cols, markers[0], markers[1], keep, MARKER_DARK)
            keep = np.concatenate([keep, P.shape[2] + np.arange(Pd.shape[2])])
            P, n, cols = np.concatenate([P, Pd], axis=2), np.concatenate([n, nd], axis=1), np.concatenate([cols, cd])
            if smooth:  # the decal's corner normals: the face's, interpolated at its corners
                cdn = np.einsum("dvw,wcd->vcd", bary, cn[:, :, src])
                cn = np.concatenate([cn, cdn / np.linalg.norm(cdn, axis=1, keepdims=True)], axis=2)
            if tex is not None:
                tex = np.concatenate([tex, np.zeros((Pd.shape[2], 3, 3))])
        if smooth:
            shaded = _shade_corners(cn, cols, AMBIENT)[keep]
        else:
            shaded = _shade(n.take(keep, axis=1), cols[keep], AMBIENT)
        return _gl.render_faces(P.take(keep, axis=2), shaded, camera, bg, None if tex is None else tex[keep], CHECKER_DARK)
    if smooth or tex is not None or markers is not None:
        return _render_per_pixel_numpy(P, n, cols, front, camera, bg, cn, tex, markers)
    zb = zbuffer(P, camera.K, camera.width, camera.height, near=camera.near, far=camera.far, front=front)
    shaded = _shade(n.take(zb.ids, axis=1), cols[zb.ids], AMBIENT)
    return zb.lookup(shaded, bg), zb.depth()


def _render_realistic(
    P: NDArray[np.float64], n: NDArray[np.float64], cols: NDArray[np.float64], front: NDArray[np.bool_] | None,
    camera: CameraModel, bg: NDArray[np.uint8], be: str, realism: Realism, rng: np.random.Generator | None,
    cn: NDArray[np.float64] | None, tex: NDArray[np.float64] | None = None,
    markers: tuple[NDArray[np.float64], list[NDArray[np.bool_]]] | None = None,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """The pipeline of ``ejsrl.world._realism``: render finer and wider, average, distort, blur, add noise."""
    s = int(realism.antialias)
    W, H = camera.width, camera.height
    lens = None
    if realism.distorted:
        lens = CameraModel(W, H, K=camera.K, distortion=realism.distortion, near=camera.near, far=camera.far)
    m = margin_for(lens) if lens is not None else 0
    fine = CameraModel(s * (W + 2 * m), s * (H + 2 * m), K=supersampled_K(camera.K, s, m), near=camera.near, far=camera.far)
    rgb, depth = _render_pinhole(P, n, cols, front, fine, bg, be, cn, tex, markers)
    img = block_mean(rgb, s)
    depth = centre_depth(depth, s)
    if lens is not None:
        K_wide = np.array(camera.K, dtype=np.float64)
        K_wide[0, 2] += m
        K_wide[1, 2] += m
        img = lens.distort(img, K_source=K_wide)
        depth = lens.distort(depth, interpolation="nearest", K_source=K_wide)
        depth[depth <= 0] = np.inf  # no source: nothing seen
    if realism.blur > 0:
        import cv2

        img = cv2.GaussianBlur(img, (0, 0), sigmaX=float(realism.blur), sigmaY=float(realism.blur), borderType=cv2.BORDER_REFLECT)
    if realism.noise > 0:
        gen = rng if rng is not None else np.random.default_rng()
        img = img + gen.standard_normal(img.shape, dtype=np.float32) * np.float32(realism.noise)
    return np.clip(np.rint(img), 0, 255).astype(np.uint8), np.ascontiguousarray(depth, dtype=np.float32)


def _noise_rng(node: Any) -> np.random.Generator:
    """The noise generator of a camera node: one per node, seeded from its name (reproducible runs)."""
    gen = node.__dict__.get("_ejs_noise_rng")
    if gen is None:
        import zlib

        gen = node.__dict__["_ejs_noise_rng"] = np.random.default_rng(zlib.crc32(node.name.encode()))
    return gen


def render(
    world: Any,
    camera: CameraModel | str,
    T_world_camera: ArrayLike | None = None,
    *,
    exclude: Sequence[str] = (),
    background: Sequence[float] = BACKGROUND,
    cull_backfaces: bool = True,
    backend: str = "auto",
    realism: Realism | None = None,
    rng: np.random.Generator | None = None,
) -> tuple[NDArray[np.uint8], NDArray[np.float32]]:
    """Render what a camera sees in ``world``: ``(rgb (H, W, 3) uint8, depth (H, W) float32)``.

    ``camera``: a ``CameraModel`` (then ``T_world_camera`` (4, 4), the camera pose in the
    world, is required) or the name of a ``CameraNode`` of the world (then its pose,
    intrinsics, resolution, near and far come from the node; a given ``T_world_camera``
    overrides the pose). ``exclude``: names of nodes not to draw (for example the robot
    link that carries the camera). ``background``: RGB in [0, 1] (default ``BACKGROUND``,
    light grey-blue). ``cull_backfaces``: skip faces seen from behind, as the browser view
    (three.js, front side) does; set False for open meshes seen from both sides.
    ``backend``: "auto" (default: OpenGL when it works here, else NumPy), "numpy" or "gl"
    (see the module docstring; "gl" raises with an install hint when it cannot run).

    ``realism``: anti-aliasing, smooth shading, lens distortion, blur and noise
    (``Realism``); by default, for a camera node, those of its properties (``antialias``,
    ``shading``, ``distortion``, ``blur``, ``noise``), none for a ``CameraModel``. Noise
    comes from ``rng`` or else, for a camera node, from a generator of the node seeded
    from its name.

    Depth is Z in the camera frame (metres along the optical axis), inf where nothing is
    seen. The output is deterministic for a given back end and machine (noise aside: the
    same sequence of frames from the same start).
    """
    if isinstance(camera, str):
        node = world[camera]
        if getattr(node, "kind", None) != "camera":
            raise ValueError(f"{camera!r} is a {node.kind}, not a camera")
        cam = CameraModel.from_node(node)
        T = node.T_world() if T_world_camera is None else np.asarray(T_world_camera, dtype=float)
        exclude = tuple(exclude) + (camera,)
        if realism is None:
            realism = Realism.from_props(node.props)
        if realism.noise > 0 and rng is None:
            rng = _noise_rng(node)
    elif isinstance(camera, CameraModel):
        if T_world_camera is None:
            raise ValueError("render(world, CameraModel, T_world_camera): the camera pose T_world_camera is required")
        cam = camera
        T = np.asarray(T_world_camera, dtype=float)
    else:
        raise TypeError(f"camera must be a CameraModel or a camera name, not {type(camera).__name__}")
    tris, rgb = world.triangles(exclude=tuple(exclude))
    return render_triangles(
        tris, rgb, cam, T, background=background, cull_backfaces=cull_backfaces, backend=backend, realism=realism, rng=rng,
        texture=texture_coords(world, tuple(exclude), tris), markers=marker_coords(world, tuple(exclude), tris),
    )


def render_depth(world: Any, camera: CameraModel | str, T_world_camera: ArrayLike | None = None, **kw: Any) -> NDArray[np.float32]:
    """The depth image alone (H, W) float32: Z in metres along the optical axis, inf where nothing is seen.

    As ``render`` (same arguments); lens distortion moves depth as it moves the image;
    anti-aliasing, blur and noise do not touch it (it is the depth at each pixel's centre).
    """
    realism = kw.pop("realism", None)
    if isinstance(camera, str) and realism is None:
        node = world[camera]
        if getattr(node, "kind", None) == "camera":
            p = Realism.from_props(node.props)
            realism = Realism(distortion=p.distortion)  # only what moves the depth
    return render(world, camera, T_world_camera, realism=realism, **kw)[1]
