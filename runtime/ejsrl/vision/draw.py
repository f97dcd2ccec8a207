"""Drawing helpers to show results: points, lines, boxes, circles, contours and text.

Each returns a new RGB (H, W, 3) uint8 image (a grey input is turned into RGB first);
colours are RGB tuples 0..255 or names ("red", "green", ...). Coordinates are ``(x, y)``;
points that are not finite are skipped. Bad input (an empty or NaN image, a wrong shape,
an unknown colour or marker) is a ``ValueError``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from ejsrl.vision._util import as_points, as_rgb, choice, image_function

__all__ = ["draw_points", "draw_lines", "draw_boxes", "draw_circles", "draw_contours", "draw_text"]

_NAMED = {
    "red": (255, 0, 0), "green": (0, 200, 0), "blue": (0, 0, 255), "yellow": (255, 255, 0), "cyan": (0, 255, 255),
    "magenta": (255, 0, 255), "white": (255, 255, 255), "black": (0, 0, 0), "orange": (255, 140, 0),
}


def _color(c: Any) -> tuple[int, int, int]:
    if isinstance(c, str):
        if c not in _NAMED:
            raise ValueError(f"unknown colour {c!r}; use an (r, g, b) tuple or one of {sorted(_NAMED)}")
        return _NAMED[c]
    try:
        r, g, b = (int(v) for v in c)
    except (TypeError, ValueError):
        raise ValueError(f"a colour is an (r, g, b) tuple of 0..255 or one of {sorted(_NAMED)}, got {c!r}") from None
    return (r, g, b)


@image_function
def draw_points(img: ArrayLike, points: ArrayLike, color: Any = "red", *, size: int = 7, marker: str = "cross", thickness: int = 1) -> NDArray[np.uint8]:
    """Mark points (N, 2) (x, y) with a ``marker`` ("cross", "x", "square", "dot") of ``size`` pixels."""
    out = as_rgb(img).copy()
    col = _color(color)
    kinds = {"cross": cv2.MARKER_CROSS, "x": cv2.MARKER_TILTED_CROSS, "square": cv2.MARKER_SQUARE}
    choice(marker, [*kinds, "dot"], "marker")
    for x, y in as_points(points):
        if not (np.isfinite(x) and np.isfinite(y)):
            continue
        p = (int(round(x)), int(round(y)))
        if marker == "dot":
            cv2.circle(out, p, max(1, size // 2), col, -1)
        else:
            cv2.drawMarker(out, p, col, kinds[marker], int(size), int(thickness))
    return out


@image_function
def draw_lines(img: ArrayLike, segments: ArrayLike, color: Any = "green", *, thickness: int = 1) -> NDArray[np.uint8]:
    """Draw segments (N, 4) ``(x1, y1, x2, y2)``, or a polyline given as points (N, 2)."""
    out = as_rgb(img).copy()
    a = np.asarray(segments, dtype=np.float64)
    if a.ndim == 2 and a.shape[1] == 2:
        a = np.column_stack([a[:-1], a[1:]])
    for x1, y1, x2, y2 in as_points(a, "segments", k=4):
        if not np.isfinite((x1, y1, x2, y2)).all():
            continue
        cv2.line(out, (int(round(x1)), int(round(y1))), (int(round(x2)), int(round(y2))), _color(color), int(thickness))
    return out


@image_function
def draw_boxes(img: ArrayLike, boxes: ArrayLike, color: Any = "yellow", *, thickness: int = 1) -> NDArray[np.uint8]:
    """Draw rectangles (N, 4) ``(x, y, width, height)`` (top-left corner and size)."""
    out = as_rgb(img).copy()
    for x, y, w, h in as_points(boxes, "boxes", k=4):
        if not np.isfinite((x, y, w, h)).all():
            continue
        cv2.rectangle(out, (int(x), int(y)), (int(x + w - 1), int(y + h - 1)), _color(color), int(thickness))
    return out


@image_function
def draw_circles(img: ArrayLike, circles: ArrayLike, color: Any = "cyan", *, thickness: int = 1) -> NDArray[np.uint8]:
    """Draw circles (N, 3) ``(x, y, radius)``."""
    out = as_rgb(img).copy()
    for x, y, r in as_points(circles, "circles", k=3):
        if not np.isfinite((x, y, r)).all():
            continue
        cv2.circle(out, (int(round(x)), int(round(y))), int(round(r)), _color(color), int(thickness))
    return out


@image_function
def draw_contours(img: ArrayLike, contours: Sequence[ArrayLike], color: Any = "magenta", *, thickness: int = 1) -> NDArray[np.uint8]:
    """Draw closed outlines, each an (M, 2) array of (x, y) points (as ``find_contours`` gives)."""
    out = as_rgb(img).copy()
    cs = [np.rint(p).astype(np.int32).reshape(-1, 1, 2) for p in (as_points(c, "contour") for c in contours) if len(p) and np.isfinite(p).all()]
    cv2.drawContours(out, cs, -1, _color(color), int(thickness))
    return out


@image_function
def draw_text(img: ArrayLike, text: str, org: tuple[float, float] = (5, 15), color: Any = "white", *, scale: float = 0.5, thickness: int = 1) -> NDArray[np.uint8]:
    """Write ``text`` with its baseline starting at ``org`` (x, y) (Hershey simplex font)."""
    out = as_rgb(img).copy()
    cv2.putText(out, str(text), (int(org[0]), int(org[1])), cv2.FONT_HERSHEY_SIMPLEX, float(scale), _color(color), int(thickness), cv2.LINE_AA)
    return out
