"""Images for viser's client in a web page: PNG written with NumPy and ``zlib``.

viser encodes an image element's picture (and image textures) with OpenCV, or else with
imageio on Pillow; the browser's Python has neither. :func:`install` makes viser's encoder
write PNG with the standard library instead, so an ``image`` element (a virtual camera's
view, an array) shows in the page as served. PNG rather than JPEG: lossless, and the page
sends it through memory, not a network.
"""

from __future__ import annotations

import struct
import zlib
from typing import Any, Literal

import numpy as np

__all__ = ["encode_png", "install"]


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(image: np.ndarray, level: int = 1) -> bytes:
    """The PNG file of ``image``: (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA, uint8 (other
    dtypes are clipped to 0-255 and rounded); ``level``: zlib's level (1: fast)."""
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = np.clip(np.rint(a.astype(np.float64)), 0, 255).astype(np.uint8)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim == 2:
        colour, channels = 0, 1
    elif a.ndim == 3 and a.shape[2] in (3, 4):
        colour, channels = (2, 3) if a.shape[2] == 3 else (6, 4)
    else:
        raise ValueError(f"an image is (H, W), (H, W, 3) or (H, W, 4), not {a.shape}")
    h, w = a.shape[:2]
    rows = np.empty((h, 1 + w * channels), dtype=np.uint8)
    rows[:, 0] = 0  # filter type 0 (none) on every row
    rows[:, 1:] = a.reshape(h, w * channels)
    header = struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
            + _chunk(b"IEND", b""))


def _encode_image_binary(image: np.ndarray, format: Literal["auto", "png", "jpeg"],
                         jpeg_quality: int | None = None) -> tuple[Literal["png"], bytes]:
    """viser's ``_encode_image_binary`` in a page: always PNG (no JPEG encoder there)."""
    from viser._scene_api import colors_to_uint8

    return "png", encode_png(colors_to_uint8(image))


def install() -> None:
    """Make viser (imported) encode images with :func:`encode_png`."""
    import viser._gui_handles as gui_handles
    import viser._scene_api as scene_api

    module: Any
    for module in (scene_api, gui_handles):
        module._encode_image_binary = _encode_image_binary
