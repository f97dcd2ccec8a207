"""The reference plant's camera: the arm as a fixed camera in the lab sees it, a JPEG video stream.

A stand-in for the webcam a remote lab points at its robot: ``fps`` times a second it reads the
arm's true joint angles, renders the arm, the table and the belt with ejsrl's own virtual camera
(:func:`ejsrl.world.render`, the NumPy rasterizer: ~2 ms a frame at 320 x 240, ~4 ms at 640 x 480),
encodes the picture as JPEG (OpenCV) and hands the frame message (:func:`._video.pack_frame`,
stamped with the capture time on the plant's clock) to every transport's sink. ``latency``
delays the hand-over (a camera pipeline's delay, to test the age shown by the app); a frame is
never queued behind a slow transport: a sink is called from this thread and a transport drops
what it cannot send.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from typing import Callable

import numpy as np

from ._core import Plant
from ._video import pack_frame

__all__ = ["PlantCamera"]


def _arm_world(width: int, height: int) -> tuple[object, object]:
    """The camera's scene: the 5-axis arm (RobUALab's geometry), its table and the belt; returns
    ``(world, robot node)``. The camera ``"cam"`` looks at the arm from the front right."""
    from ejsrl.robotics import Link, Robot
    from ejsrl.vision.camera import look_at
    from ejsrl.world import World
    from ejsrl.world.robot_node import RobotNode
    from ejsrl.world.scene import Box, CameraNode

    def at(x: float, y: float, z: float) -> np.ndarray:
        T = np.eye(4)
        T[:3, 3] = (x, y, z)
        return T

    world = World()
    arm = Robot([Link(d=0.35, alpha=math.pi / 2), Link(a=0.22), Link(a=0.22), Link(a=0.15), Link()], name="plant")
    node = RobotNode("arm", model=arm, q=np.zeros(5))
    world.add(node)
    node.set(model=arm, q=np.zeros(5))
    world.add(Box("table", size=(1.2, 1.2, 0.02), color="burlywood", T_parent_local=at(0, 0, -0.01)))
    world.add(Box("belt", size=(0.16, 0.8, 0.05), color="dimgray", T_parent_local=at(0.35, -0.4, 0.025)))
    world.add(CameraNode("cam", T_parent_local=look_at((1.1, -0.9, 0.85), (0.0, 0.0, 0.3)), fov=50.0,
                         resolution=(width, height)))
    return world, node


class PlantCamera:
    """The plant's camera thread: ``width`` x ``height`` pixels, ``fps`` frames a second, JPEG
    ``quality`` (1-100), hand-over delayed by ``latency`` s. Sinks take one frame message (bytes)."""

    def __init__(self, plant: Plant, *, width: int = 320, height: int = 240, fps: float = 10.0,
                 quality: int = 80, latency: float = 0.0) -> None:
        if not (16 <= width <= 1920 and 16 <= height <= 1080):
            raise ValueError(f"a camera of {width} x {height} pixels: give 16..1920 x 16..1080")
        if not 0 < fps <= 60:
            raise ValueError(f"a camera at {fps} frames/s: give more than 0 and at most 60")
        self.plant, self.width, self.height, self.fps = plant, width, height, fps
        self.quality, self.latency = int(quality), max(0.0, float(latency))
        self.sinks: list[Callable[[bytes], None]] = []
        self.seq = 0
        self.frames = 0
        self.render_s = 0.0                                 # CPU time of the last capture, s
        self._world, self._node = _arm_world(width, height)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def capture(self) -> bytes:
        """Render the arm as it is now and return the frame message (header line and JPEG)."""
        import cv2

        from ejsrl.world import render

        c0 = time.process_time()
        t, q = self.plant.pose()
        self._node.set(q=q)
        rgb, _ = render(self._world, "cam", backend="numpy")
        ok, jpeg = cv2.imencode(".jpg", np.ascontiguousarray(rgb[:, :, ::-1]), [cv2.IMWRITE_JPEG_QUALITY, self.quality])
        if not ok:  # pragma: no cover - OpenCV encodes any uint8 picture
            raise RuntimeError("OpenCV could not encode the camera's picture")
        self.seq += 1
        self.render_s = time.process_time() - c0
        return pack_frame(jpeg.tobytes(), t=t, seq=self.seq, w=self.width, h=self.height, boot=self.plant.boot)

    def start(self) -> None:
        self._thread = threading.Thread(target=self._run, name="ejsrl-plant-camera", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)

    def _deliver(self, frame: bytes) -> None:
        self.frames += 1
        for sink in list(self.sinks):
            try:
                sink(frame)
            except Exception:  # noqa: BLE001 - a transport going away must not stop the camera
                pass

    def _run(self) -> None:
        period = 1.0 / self.fps
        nxt = time.monotonic()
        delayed: deque[tuple[float, bytes]] = deque()
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= nxt:
                frame = self.capture()
                if self.latency > 0:
                    delayed.append((now + self.latency, frame))
                else:
                    self._deliver(frame)
                nxt = max(nxt + period, time.monotonic() - period)
            now = time.monotonic()
            while delayed and delayed[0][0] <= now:
                self._deliver(delayed.popleft()[1])
            wake = min(nxt, delayed[0][0]) if delayed else nxt
            self._stop.wait(max(0.0, wake - time.monotonic()))
