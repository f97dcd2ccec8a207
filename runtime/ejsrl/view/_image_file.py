"""The picture of a 2D ``image`` element's file (``file: photo.jpg``), as the panel shows it.

Served, OpenCV reads the file (PNG, JPEG, BMP, TIFF, WebP, ...) with ``cv2.IMREAD_COLOR``: an
8-bit RGB picture (alpha dropped, grey made RGB, 16-bit scaled to 8 bits). A lab built with
``ejsgen build --web`` runs in a browser, whose Python has no OpenCV: the build reads each such
file here, with the same OpenCV, and writes beside it a copy (:data:`WEB_COPY`: a PNG of those
very pixels, each row stored as its difference from the row above, PNG's ``Up`` filter), which
:func:`read_image_file` reads back in the page with zlib and NumPy alone. The page thus shows
the served picture pixel for pixel, whatever the file's format.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np

from ejsrl.web._png import _chunk  # the PNG chunk writer of the page's image encoder

__all__ = ["WEB_COPY", "read_image_file", "write_web_copy", "encode_copy", "decode_copy"]

#: the suffix of the decoded copy a web build writes beside an image file (``map.jpg.web.png``)
WEB_COPY = ".web.png"
_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: the most pixels a picture may have (a 2D panel is at most a few thousand pixels wide)
MAX_PIXELS = 50_000_000


def read_image_file(path: Path, shown: str | None = None) -> np.ndarray:
    """The (H, W, 3) uint8 RGB picture of the image file ``path`` as OpenCV reads it; from its
    decoded copy (``path`` + :data:`WEB_COPY`) when there is one (a lab in a browser). ``shown``:
    the file's name in an error (the spec's text; default: the file's name)."""
    copy = Path(f"{path}{WEB_COPY}")
    if copy.is_file():
        return decode_copy(copy.read_bytes())
    import cv2

    bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if bgr is None:
        raise ValueError(f"the image file {shown or Path(path).name!r} could not be read")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def write_web_copy(path: Path, shown: str | None = None) -> Path:
    """Write the decoded copy of the image file ``path`` beside it; the copy's path."""
    copy = Path(f"{path}{WEB_COPY}")
    copy.write_bytes(encode_copy(read_image_file(path, shown)))
    return copy


def encode_copy(rgb: np.ndarray) -> bytes:
    """A PNG file of ``rgb`` ((H, W, 3) uint8): 8-bit RGB, not interlaced, every row with the
    ``Up`` filter (type 2: its bytes minus the row above's, modulo 256), zlib at level 9."""
    a = np.ascontiguousarray(rgb, dtype=np.uint8)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"a picture is (H, W, 3), not {a.shape}")
    h, w = a.shape[:2]
    rows = a.reshape(h, w * 3)
    filtered = np.empty((h, 1 + w * 3), dtype=np.uint8)
    filtered[:, 0] = 2
    filtered[:, 1:] = np.diff(rows, axis=0, prepend=np.zeros((1, w * 3), dtype=np.uint8))  # uint8: modulo 256
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return _SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(filtered.tobytes(), 9)) + _chunk(b"IEND", b"")


def decode_copy(data: bytes) -> np.ndarray:
    """The (H, W, 3) uint8 picture of a PNG written by :func:`encode_copy` (filters ``None`` or
    ``Up``); :class:`ValueError` for any other file (a copy is never anything else)."""
    if not data.startswith(_SIGNATURE):
        raise ValueError("not a PNG file")
    pos, header, idat = len(_SIGNATURE), b"", []
    while pos + 12 <= len(data):
        n, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + n]
        if len(body) != n or struct.unpack(">I", data[pos + 8 + n : pos + 12 + n])[0] != zlib.crc32(kind + body) & 0xFFFFFFFF:
            raise ValueError("a damaged PNG chunk")
        if kind == b"IHDR":
            header = body
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + n
    if len(header) != 13:
        raise ValueError("a PNG without its header")
    w, h, depth, colour, _compression, _filter, interlace = struct.unpack(">IIBBBBB", header)
    if (depth, colour, interlace) != (8, 2, 0) or not 0 < w * h <= MAX_PIXELS:
        raise ValueError(f"not a decoded picture of a web build (depth {depth}, colour type {colour}, interlace {interlace}, {w} x {h})")
    raw = zlib.decompress(b"".join(idat))
    if len(raw) != h * (1 + w * 3):
        raise ValueError("a PNG whose pixels do not fill its size")
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(h, 1 + w * 3)
    kinds = rows[:, 0]
    if not np.all((kinds == 0) | (kinds == 2)):
        raise ValueError("a PNG row filter other than None or Up")
    if np.all(kinds == 2):
        out = np.cumsum(rows[:, 1:], axis=0, dtype=np.uint8)  # Up on every row: a running sum, modulo 256
    else:
        out = rows[:, 1:].copy()
        for i in np.nonzero(kinds == 2)[0]:
            if i:
                out[i] += out[i - 1]  # the row above is decoded already
    return out.reshape(h, w, 3)
