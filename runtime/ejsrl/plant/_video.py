"""The plant's video frames on the wire, and the app's clock of a plant it cannot share a clock with.

A frame is one message: a JSON header line, ``\\n``, then the picture as a baseline or progressive
JPEG::

    {"t": 1234.567, "seq": 42, "w": 320, "h": 240, "boot": "3f2a..."}\\n<JPEG bytes>

``t`` is the capture time on the plant's clock (s; the same clock as the state's ``t``), ``seq``
counts frames from 1 in one life of the plant (``boot``), ``w`` x ``h`` is the picture in pixels.

The app never decodes a frame: :func:`parse_frame` checks the header and the JPEG's own structure
(start and end markers, the frame header's size equal to ``w`` x ``h``, nothing larger than
:data:`MAX_FRAME_BYTES`) and the bytes go to the browser as they came (a JPEG image element).

The plant's clock is another machine's: :class:`PlantClock` maps it onto the app's monotonic
clock from the state messages (the plant stamps each with its ``t`` just before sending it), the
way NTP's clock filter does: over a sliding window the smallest ``arrival - t`` is the offset plus
the fastest transit, so ``age = now - (t_capture + offset)`` is a frame's age since capture on the
app's clock, at most the fastest one-way transit (~0.1 ms on loopback, ~1 ms on a LAN) too young.
"""

from __future__ import annotations

import json
import math
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

__all__ = ["MAX_FRAME_BYTES", "VideoFrame", "PlantClock", "pack_frame", "parse_frame", "jpeg_size"]

#: the largest frame message an app accepts (a 1920 x 1080 JPEG at quality 90 is ~0.5 MB)
MAX_FRAME_BYTES = 1 << 20
#: the largest picture side an app accepts, pixels
MAX_SIDE = 4096
_MAX_HEADER = 512


@dataclass(frozen=True)
class VideoFrame:
    """One frame as the app keeps it: ``jpeg`` bytes of a ``w`` x ``h`` picture captured at
    plant time ``t`` (s), number ``seq``, arrived at app time ``arrived`` (``time.monotonic()``, s)."""

    jpeg: bytes
    t: float
    seq: int
    w: int
    h: int
    boot: str
    arrived: float


def pack_frame(jpeg: bytes, *, t: float, seq: int, w: int, h: int, boot: str) -> bytes:
    """The frame message of a JPEG picture (see the module docstring)."""
    header = json.dumps({"t": t, "seq": seq, "w": w, "h": h, "boot": boot}, separators=(",", ":"))
    return header.encode() + b"\n" + jpeg


def jpeg_size(data: bytes) -> tuple[int, int] | None:
    """``(width, height)`` from a JPEG's frame header (SOF0..SOF15 but DHT/JPG/DAC), or None when
    ``data`` is not a whole JPEG (no start or end marker, a segment running past the end)."""
    if len(data) < 4 or data[:2] != b"\xff\xd8" or data[-2:] != b"\xff\xd9":
        return None
    i, n = 2, len(data)
    while i + 4 <= n:
        if data[i] != 0xFF:
            return None
        marker = data[i + 1]
        if marker == 0xFF:                         # fill byte
            i += 1
            continue
        if marker in (0x01, *range(0xD0, 0xD8)):   # markers without a length
            i += 2
            continue
        length = int.from_bytes(data[i + 2:i + 4], "big")
        if length < 2 or i + 2 + length > n:
            return None
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            if length < 7:
                return None
            h = int.from_bytes(data[i + 5:i + 7], "big")
            w = int.from_bytes(data[i + 7:i + 9], "big")
            return w, h
        if marker == 0xDA:                         # scan data before any frame header
            return None
        i += 2 + length
    return None


def parse_frame(payload: bytes, arrived: float) -> VideoFrame | str:
    """The frame in a message, or why it is refused (the app drops it and counts it)."""
    if len(payload) > MAX_FRAME_BYTES:
        return f"a frame of {len(payload)} bytes is over {MAX_FRAME_BYTES}"
    cut = payload.find(b"\n", 0, _MAX_HEADER)
    if cut < 0:
        return "a frame starts with a JSON header line"
    try:
        head = json.loads(payload[:cut])
        t, seq, w, h = float(head["t"]), int(head["seq"]), int(head["w"]), int(head["h"])
        boot = str(head.get("boot", ""))[:32]
    except (ValueError, TypeError, KeyError, UnicodeDecodeError):
        return "a frame's header needs t, seq, w and h"
    if not math.isfinite(t) or not (0 < w <= MAX_SIDE and 0 < h <= MAX_SIDE):
        return "a frame's time is not finite or its size is out of range"
    jpeg = payload[cut + 1:]
    if jpeg_size(jpeg) != (w, h):
        return f"a frame is not a whole {w} x {h} JPEG"
    return VideoFrame(jpeg, t, seq, w, h, boot, arrived)


class PlantClock:
    """The plant's clock on the app's (monotonic, s): ``local = plant + offset``.

    :meth:`add` takes each state message's plant time with its arrival time; :attr:`offset` is the
    smallest ``arrival - t`` over the last ``window`` s (kept as per-second minima, so a plant
    whose clock drifts slowly is followed). :meth:`reset` on a plant's restart (another clock)."""

    def __init__(self, window: float = 30.0) -> None:
        self.window = window
        self._blocks: deque[tuple[float, float]] = deque()   # (second it started, min of arrival - t)
        self.offset: float | None = None

    def reset(self) -> None:
        self._blocks.clear()
        self.offset = None

    def add(self, plant_t: Any, arrived: float | None = None) -> None:
        try:
            t = float(plant_t)
        except (TypeError, ValueError):
            return
        if not math.isfinite(t):
            return
        now = time.monotonic() if arrived is None else arrived
        d = now - t
        blocks = self._blocks
        if blocks and now - blocks[-1][0] < 1.0:
            if d >= blocks[-1][1]:
                return
            blocks[-1] = (blocks[-1][0], d)
        else:
            blocks.append((now, d))
            while blocks and now - blocks[0][0] > self.window:
                blocks.popleft()
        self.offset = min(b[1] for b in blocks)

    def age(self, plant_t: float, now: float | None = None) -> float | None:
        """Seconds since plant time ``plant_t`` on the app's clock, or None before any state."""
        if self.offset is None:
            return None
        return (time.monotonic() if now is None else now) - (plant_t + self.offset)
