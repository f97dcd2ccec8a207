"""Real image sources: a camera, a stream, a video file or a sequence of image files.

``ImageSource(x)`` gives RGB frames (H, W, 3) uint8, the same as ``capture("cam")`` gives
for a virtual camera, so the same pipeline (``Pipeline``, ``detect_markers``, SUSAN...)
runs on either. What ``x`` may be:

- a whole number (``0``, ``1``...): the camera of that index on the machine that runs the
  app (``cv2.VideoCapture(index)``; a served app's camera is the server's, not the
  browser's);
- a URL (``rtsp://...``, ``http://...``, ``https://...``): a network stream;
- a video file (``.mp4``, ``.avi``, ``.mkv``, ...; in a spec, list it under ``assets:``
  and give its path, so the built app carries it);
- a folder of images (``.png``, ``.jpg``, ``.bmp``, ``.tif``, read in name order) or a
  glob pattern (``"frames/*.png"``).

A source belongs to whoever made it: made in a spec's variables it is the session's (every
browser tab reads its own), and it is closed when dropped. A camera or file that cannot be
opened is a ``ValueError`` that says which and why, when the source is made; a camera that
stops giving frames is a ``RuntimeError`` at ``read``.

Files and sequences end: ``read()`` then starts again from the first frame (``loop=True``,
the default) or raises ``EOFError``; ``frame_at(t)`` gives the frame shown at time ``t``
seconds (a file's own frame rate, or ``fps=``), which keeps a video in step with the
simulation's clock. ``size=(w, h)`` resizes every frame (area averaging).
"""

from __future__ import annotations

import glob
import math
import os
import threading
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

__all__ = ["IMAGE_SUFFIXES", "CameraSources", "ImageSource"]

#: image files a folder source reads
IMAGE_SUFFIXES: tuple[str, ...] = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp", ".pgm", ".ppm")
_URL_SCHEMES = ("rtsp://", "rtmp://", "http://", "https://", "udp://", "tcp://")


def _rgb(frame: NDArray[Any]) -> NDArray[np.uint8]:
    """An OpenCV frame (BGR, BGRA, grey; uint8 or uint16) -> RGB uint8."""
    if frame.dtype == np.uint16:
        frame = (frame.astype(np.float32) / 257.0 + 0.5).astype(np.uint8)
    elif frame.dtype != np.uint8:
        frame = np.clip(frame, 0, 255).astype(np.uint8)
    if frame.ndim == 2:
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2RGB)
    if frame.shape[2] == 4:
        return cv2.cvtColor(frame, cv2.COLOR_BGRA2RGB)
    return cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)


class ImageSource:
    """Frames from a camera index, a URL, a video file, a folder of images or a glob pattern.

    ``loop``: start a file or sequence again at its end (else ``EOFError``). ``fps``: the
    frame rate of a sequence (default 30) or, for a video, instead of its own. ``size``:
    ``(width, height)`` of every frame returned (None: as read).
    """

    def __init__(self, source: int | str | os.PathLike[str], *, loop: bool = True, fps: float | None = None,
                 size: tuple[int, int] | None = None) -> None:
        self._lock = threading.Lock()
        self._cap: Any = None
        self._files: list[str] = []
        self.loop = bool(loop)
        self.size = None if size is None else (int(size[0]), int(size[1]))
        if self.size is not None and min(self.size) < 1:
            raise ValueError(f"size is (width, height) in pixels >= 1, got {size!r}")
        if fps is not None and not (math.isfinite(float(fps)) and float(fps) > 0):
            raise ValueError(f"fps must be a number of frames a second > 0, got {fps!r}")
        #: frames read so far from the start (or the last loop); the next ``read`` gives frame ``index``
        self.index = 0
        if isinstance(source, bool):
            raise ValueError(f"an image source is a camera index, a URL, a video file or images, not {source!r}")
        if isinstance(source, (int, np.integer)):
            self.kind = "camera"
            self.name = f"camera {int(source)}"
            self._cap = cv2.VideoCapture(int(source))
            if not self._cap.isOpened():
                self._cap.release()
                raise ValueError(
                    f"cannot open camera {int(source)}: there is no such camera on this machine (the one that runs the "
                    "app; a served app cannot use the browser's camera). Plug one in, try another index, or read a "
                    "video file instead: ImageSource('clip.mp4')"
                )
            self.fps = float(fps) if fps is not None else (self._cap.get(cv2.CAP_PROP_FPS) or 30.0)
            self.frame_count = 0
            return
        text = os.fspath(source)
        if text.lower().startswith(_URL_SCHEMES):
            self.kind = "stream"
            self.name = text
            self._cap = cv2.VideoCapture(text)
            if not self._cap.isOpened():
                self._cap.release()
                raise ValueError(f"cannot open the stream {text!r}: nothing answered there, or OpenCV cannot decode it")
            self.fps = float(fps) if fps is not None else (self._cap.get(cv2.CAP_PROP_FPS) or 30.0)
            self.frame_count = 0
            return
        path = Path(text)
        self.name = text
        if path.is_dir():
            self._files = sorted(str(p) for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
            if not self._files:
                raise ValueError(f"the folder {text!r} has no images ({', '.join(IMAGE_SUFFIXES)})")
        elif any(ch in text for ch in "*?["):
            self._files = sorted(f for f in glob.glob(text) if Path(f).suffix.lower() in IMAGE_SUFFIXES)
            if not self._files:
                raise ValueError(f"no image files match {text!r}")
        elif not path.exists():
            raise ValueError(f"cannot open {text!r}: no such file or folder (in a spec, list it under assets:)")
        elif path.suffix.lower() in IMAGE_SUFFIXES:
            self._files = [text]
        if self._files:
            self.kind = "images"
            self.fps = float(fps) if fps is not None else 30.0
            self.frame_count = len(self._files)
            return
        self.kind = "video"
        self._cap = cv2.VideoCapture(text)
        if not self._cap.isOpened():
            self._cap.release()
            raise ValueError(f"cannot read the video {text!r}: OpenCV (FFmpeg) cannot decode this file")
        self.fps = float(fps) if fps is not None else (self._cap.get(cv2.CAP_PROP_FPS) or 30.0)
        self.frame_count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)

    # -- reading -------------------------------------------------------------------------------------
    def _finish(self, frame: NDArray[Any]) -> NDArray[np.uint8]:
        rgb = _rgb(frame)
        if self.size is not None and (rgb.shape[1], rgb.shape[0]) != self.size:
            rgb = cv2.resize(rgb, self.size, interpolation=cv2.INTER_AREA)
        return rgb

    def _read_file(self, i: int) -> NDArray[np.uint8]:
        frame = cv2.imread(self._files[i], cv2.IMREAD_UNCHANGED)
        if frame is None:
            raise RuntimeError(f"cannot read the image {self._files[i]!r} of {self.name!r}: not an image OpenCV reads")
        return self._finish(frame)

    def _wrap(self) -> None:
        if not self.loop:
            raise EOFError(f"{self.name!r} has no more frames (after {self.index}); ImageSource(..., loop=True) starts it again")
        self.index = 0
        if self._cap is not None:
            self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)

    def read(self) -> NDArray[np.uint8]:
        """The next frame, RGB (H, W, 3) uint8."""
        with self._lock:
            if self._files:
                if self.index >= len(self._files):
                    self._wrap()
                out = self._read_file(self.index)
                self.index += 1
                return out
            if self._cap is None:
                raise RuntimeError(f"{self.name!r} is closed")
            ok, frame = self._cap.read()
            if not ok and self.kind == "video":
                self._wrap()
                ok, frame = self._cap.read()
            if not ok or frame is None:
                raise RuntimeError(f"{self.name} gave no frame (unplugged, or the stream ended)")
            self.index += 1
            return self._finish(frame)

    def frame_at(self, t: float) -> NDArray[np.uint8]:
        """The frame shown at time ``t`` seconds from the start (frame ``floor(t * fps)``; looped
        or the last frame past the end). A camera or stream gives its newest frame."""
        if self.kind in ("camera", "stream"):
            return self.read()
        t = float(t)
        if not math.isfinite(t) or t < 0:
            raise ValueError(f"frame_at(t): t is a time in seconds >= 0, got {t!r}")
        n = self.frame_count
        i = int(math.floor(t * self.fps + 1e-9))
        if n > 0:
            i = i % n if self.loop else min(i, n - 1)
        with self._lock:
            if self._files:
                self.index = i + 1
                return self._read_file(i)
            if i != self.index:
                self._cap.set(cv2.CAP_PROP_POS_FRAMES, i)
                self.index = i
        return self.read()

    # -- life ------------------------------------------------------------------------------------
    def close(self) -> None:
        """Let go of the camera or file (a closed source reads no more)."""
        with self._lock:
            if self._cap is not None:
                self._cap.release()
                self._cap = None
            self._files = []

    def __del__(self) -> None:
        try:
            if self._cap is not None:
                self._cap.release()
        except Exception:  # noqa: BLE001 - interpreter shutdown
            pass

    def __enter__(self) -> ImageSource:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"ImageSource({self.name!r}, {self.kind}, {self.fps:g} fps)"


class CameraSources:
    """The real sources of one session's ``camera`` elements (their ``source`` property), opened
    on the first ``capture`` and kept: each session (browser tab) has its own, so every tab reads
    its own video from its own start, and the sources close with the session.

    ``base_dir``: the app's folder, where a source's files are (its assets).
    """

    def __init__(self, base_dir: str | os.PathLike[str] = ".") -> None:
        self.base_dir = Path(base_dir)
        self._open: dict[str, tuple[Any, ImageSource]] = {}
        self._lock = threading.Lock()

    def source_of(self, name: str, source: Any) -> ImageSource:
        """The open source of camera ``name`` (opened now if it is not yet, or if the spec's value
        changed). A camera, stream or file that cannot be opened is a ``ValueError`` naming the
        camera element and what to do; it is tried again on the next capture (a camera plugged in
        meanwhile is then found)."""
        with self._lock:
            kept = self._open.get(name)
            if kept is not None and kept[0] == source:
                return kept[1]
            what = source if isinstance(source, int) or "://" in str(source) else str(self.base_dir / str(source))
            try:
                src = ImageSource(what)
            except ValueError as e:  # what to do, said as a camera element's source is written
                why = str(e).replace("read a video file instead: ImageSource('clip.mp4')", "give the camera a video file instead (source: clip.mp4)")
                raise ValueError(f"camera '{name}' (source {source!r}): {why}") from None
            if kept is not None:
                kept[1].close()
            self._open[name] = (source, src)
            return src

    def frame(self, name: str, source: Any, size: tuple[int, int], t: float | None) -> NDArray[np.uint8]:
        """Camera ``name``'s frame now, RGB (h, w, 3) uint8 with ``size = (w, h)``: a file's or image
        sequence's frame at time ``t`` seconds (its own frame rate, looped; the next frame when the
        model has no time), a camera's or stream's newest."""
        src = self.source_of(name, source)
        try:
            rgb = src.read() if t is None or src.kind in ("camera", "stream") else src.frame_at(max(float(t), 0.0))
        except RuntimeError as e:  # unplugged, or the stream ended
            with self._lock:
                if self._open.get(name, (None, None))[1] is src:
                    del self._open[name]
            src.close()
            raise RuntimeError(f"camera '{name}' (source {source!r}): {e}") from None
        w, h = int(size[0]), int(size[1])
        if rgb.shape[1] != w or rgb.shape[0] != h:
            shrink = rgb.shape[1] > w and rgb.shape[0] > h
            rgb = cv2.resize(rgb, (w, h), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        return rgb

    def close(self) -> None:
        """Let go of every source."""
        with self._lock:
            for _, src in self._open.values():
                src.close()
            self._open.clear()
