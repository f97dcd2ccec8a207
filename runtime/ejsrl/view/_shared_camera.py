"""Every tab's camera of a shared view (``--shared``), moved in step with the scene.

viser sends each tab two streams of websocket messages: the server's (the scene, which every tab
of a shared view shows) and the tab's own (its camera: ``client.camera``). A frame's poses and a
followed object's camera moves therefore travelled in two websocket messages that the browser
could take in different animation frames: the followed object jumped off the centre for a frame
(1 screenshot in 8 off by more than 4 px, up to 113 px, in a loaded browser test). A shared
view's camera is the same for every tab, so a frame's camera moves go in the server's stream,
right after the scene's poses of that frame: :class:`SharedCamera` stands for every tab's camera
where ``ejsrl.view._camera`` sets one (position, look-at point, up, field of view).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from viser import _messages

__all__ = ["SharedCamera"]


class SharedCamera:
    """The camera of every tab of ``server``, set through the server's (broadcast) message queue.

    ``cameras()``: the tabs' own camera handles (for the look-at point they last reported).
    Setting ``position`` moves the look-at point along, as viser's own camera handle does."""

    def __init__(self, server: Any, cameras: Any) -> None:
        self._server = server
        self._cameras = cameras
        #: the look-at point last sent (world frame, metres), None until one is sent
        self._look_at: np.ndarray | None = None
        self._position: np.ndarray | None = None

    def _send(self, message: Any) -> None:
        self._server._websock_server.queue_message(message)

    def _reported(self, attr: str) -> np.ndarray:
        for camera in self._cameras():
            state = getattr(camera, "_state", None)
            if state is not None and getattr(state, "update_timestamp", 0.0) != 0.0:
                return np.asarray(getattr(state, attr), dtype=float)
        return np.zeros(3)

    @property
    def look_at(self) -> np.ndarray:
        return self._look_at if self._look_at is not None else self._reported("look_at")

    @look_at.setter
    def look_at(self, value: Any) -> None:
        self._look_at = np.asarray(value, dtype=float).reshape(3)
        self._send(_messages.SetCameraLookAtMessage(tuple(float(v) for v in self._look_at)))

    @property
    def position(self) -> np.ndarray:
        return self._position if self._position is not None else self._reported("position")

    @position.setter
    def position(self, value: Any) -> None:
        new = np.asarray(value, dtype=float).reshape(3)
        offset = new - self.position
        self._position = new
        self._send(_messages.SetCameraPositionMessage(tuple(float(v) for v in new)))
        self.look_at = self.look_at + offset

    @property
    def up_direction(self) -> np.ndarray:
        return self._reported("up_direction")

    @up_direction.setter
    def up_direction(self, value: Any) -> None:
        self._send(_messages.SetCameraUpDirectionMessage(tuple(float(v) for v in np.asarray(value, dtype=float).reshape(3))))

    @property
    def fov(self) -> float:
        for camera in self._cameras():
            state = getattr(camera, "_state", None)
            if state is not None:
                return float(state.fov)
        return 0.0

    @fov.setter
    def fov(self, value: float) -> None:
        self._send(_messages.SetCameraFovMessage(float(value)))
