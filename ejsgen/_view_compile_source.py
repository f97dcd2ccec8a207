"""Build-time check of a camera element's ``source``: a real camera, a stream, a video or images.

``source`` makes a scene's ``camera`` read frames from the real world instead of rendering
the virtual scene (``ejsrl.vision.sources``): a whole number is a camera index on the
machine that runs the app; a text that starts with a URL scheme (``rtsp://``, ``http://``...)
is a stream; any other text is a path relative to the spec: a video file, an image file, a
folder of images, or a glob pattern of images. Files are checked here (inside the spec's
folder, present, of a kind OpenCV reads) and copied into the app as its assets, so a built
app or its ``.pyz`` carries them; a camera index or a URL can only be tried when the app runs
(a missing camera is a message in the page, ``ejsrl.vision.sources.CameraSources``).
"""

from __future__ import annotations

import glob
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any

from ejsgen._suggest import closest
from ejsgen.errors import SpecError

if TYPE_CHECKING:
    from ejsgen._view_compile import ViewCompiler

__all__ = ["VIDEO_SUFFIXES", "compile_source"]

#: video files a camera's ``source`` may name (what OpenCV's FFmpeg back end reads)
VIDEO_SUFFIXES = (".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv", ".ogv")
_URL_SCHEMES = ("rtsp://", "rtmp://", "http://", "https://", "udp://", "tcp://")
_HINT = ("a camera index (0), a URL (rtsp://..., http://...), a video file (clip.mp4), an image, "
         "a folder of images (frames/) or a glob pattern (\"frames/*.png\"), relative to the spec")


def _images() -> tuple[str, ...]:
    from ejsrl.vision.sources import IMAGE_SUFFIXES

    return IMAGE_SUFFIXES


def compile_source(vc: ViewCompiler, value: Any, path: tuple, base: str, what: str) -> Any:
    """The app's value of a camera's ``source``: the camera index (int), the URL, or the asset
    path of the file, folder or pattern (every image or the video registered as an asset).
    Bad values are ``SpecError``s at ``path`` that say what a source may be."""
    c = vc.c
    where = c.loc(path)
    if isinstance(value, bool) or (isinstance(value, int) and value < 0):
        c.errors.append(SpecError(where, f"{what} is {value!r}: a camera index is a whole number >= 0", _HINT))
        return None
    if isinstance(value, int):
        return value
    text = str(value).strip()
    if not text:
        c.errors.append(SpecError(where, f"{what} is empty", _HINT))
        return None
    if text.isdigit():  # "0" in quotes: the camera index the user meant
        return int(text)
    if text.lower().startswith(_URL_SCHEMES):
        return text
    if "://" in text:
        scheme = text.split("://", 1)[0] + "://"
        guess = closest(scheme, _URL_SCHEMES)
        c.errors.append(SpecError(where, f"{what}: OpenCV reads no '{scheme}' stream",
                                  f"did you mean '{guess}'?" if guess else f"a stream is one of {', '.join(_URL_SCHEMES)}"))
        return None
    images = _images()
    folder = c.spec_dir.resolve()
    rel = PurePosixPath(text.replace("\\", "/"))
    if any(ch in text for ch in "*?["):
        if rel.is_absolute() or ".." in rel.parts:
            c.errors.append(SpecError(where, f"{what}: the pattern '{text}' must stay inside the spec's folder", _HINT))
            return None
        found = sorted(p for p in glob.glob(str(folder / text)) if Path(p).suffix.lower() in images)
        if not found:
            c.errors.append(SpecError(where, f"{what}: no image files match '{text}'", f"images are {', '.join(images)}; {_HINT}"))
            return None
        for p in found:
            c.asset(Path(p).relative_to(folder).as_posix(), path, "image of the camera's source")
        return text
    real = folder / rel
    if real.is_dir():
        files = sorted(p for p in real.iterdir() if p.suffix.lower() in images)
        if not files:
            c.errors.append(SpecError(where, f"{what}: the folder '{text}' holds no images", f"images are {', '.join(images)}"))
            return None
        for p in files:
            c.asset((rel / p.name).as_posix(), path, "image of the camera's source")
        return rel.as_posix()
    if not real.exists() and not rel.is_absolute() and ".." not in rel.parts:
        near = [p.relative_to(folder).as_posix() for p in (folder / rel.parent).glob("*")
                if p.suffix.lower() in VIDEO_SUFFIXES + images or p.is_dir()] if (folder / rel.parent).is_dir() else []
        guess = closest(rel.as_posix(), near)
        c.errors.append(SpecError(where, f"{what}: the file '{text}' does not exist",
                                  f"did you mean '{guess}'?" if guess else "paths are relative to the spec's folder; " + _HINT))
        return None
    if real.suffix.lower() not in VIDEO_SUFFIXES + images:
        c.errors.append(SpecError(where, f"{what}: '{text}' is neither a video nor an image OpenCV reads",
                                  f"videos are {', '.join(VIDEO_SUFFIXES)}; images {', '.join(images)}"))
        return None
    return c.asset(text, path, "camera's source")
