"""A test video of known content, written with OpenCV's own writer: a white 20 px square moving
4 px a frame to the right over dark blue, so every frame's content is known (``true_x``)."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

#: frame width and height (px), frames, frames a second
W, H, N, FPS = 160, 120, 24, 12.0


def frame(i: int) -> np.ndarray:
    """BGR frame i (H, W, 3) uint8: the square's left edge at x = 10 + 4 i, on dark blue."""
    img = np.zeros((H, W, 3), np.uint8)
    img[:] = (90, 20, 10)
    img[50:70, 10 + 4 * i : 30 + 4 * i] = 255
    return img


def true_x(i: int, scale: float = 1.0) -> float:
    """The square's centre column in frame i, in an image ``scale`` times the video's width."""
    return (10 + 4 * i + 10) * scale - 0.5


def write_video(path: Path) -> Path:
    """The N frames as an MJPG video at FPS frames a second, at ``path``."""
    out = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), FPS, (W, H))
    assert out.isOpened()
    for i in range(N):
        out.write(frame(i))
    out.release()
    return path
