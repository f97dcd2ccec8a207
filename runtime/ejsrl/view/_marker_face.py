"""A solid's fiducial-marker texture in the browser's 3D view, as the virtual camera sees it.

A box, cylinder or mesh whose ``texture`` is a marker (``"aruco_4x4_50:7"``; see
``ejsrl.world.rendering``) shows it to ``capture()`` on its faces that look along its +z axis:
``texture_size`` metres a side, centred on the node's origin, column 0 towards -x and row 0
towards +y, black cells the face's colour times ``MARKER_DARK``. The browser's view draws the
same picture as an image node (a textured square, one texel a cell scaled up so that the cells
stay sharp) just above the node's highest point along +z, a child of the node's frame: it
moves, turns and hides with the node in the same frame.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["marker_face_key", "add_marker_face"]

#: pixels of the sent picture per marker cell (nearest-neighbour: the cells' edges stay sharp)
CELL_PX = 16


def marker_face_key(node: Any, color: tuple[int, int, int]) -> tuple | None:
    """What the marker face of ``node`` depends on (dictionary, id, side, height, colour); None if it
    has no marker texture (or one that is malformed: the virtual camera reports that)."""
    from ejsrl.vision.markers import parse_marker_texture
    from ejsrl.world.rendering import DEFAULT_TEXTURE_SIZE

    tex = node.props.get("texture")
    if not isinstance(tex, str) or ":" not in tex:
        return None
    try:
        marker = parse_marker_texture(tex)
    except ValueError:
        return None
    if marker is None:
        return None
    raw = node.props.get("texture_size")
    try:
        side = DEFAULT_TEXTURE_SIZE if raw is None else float(raw)
    except (TypeError, ValueError):
        return None
    top = _top(node)
    if top is None or not (np.isfinite(side) and side > 0):
        return None
    return (*marker, side, top, tuple(color))


def _top(node: Any) -> float | None:
    """The node's highest point along its own +z (metres), None if it has no geometry."""
    try:
        parts = node.parts()
    except Exception:
        return None
    tops = []
    for part in parts:
        v = np.asarray(part.vertices, dtype=float).reshape(-1, 3)
        if len(v) == 0:
            continue
        if part.T_node_part is not None:
            T = np.asarray(part.T_node_part, dtype=float)
            v = v @ T[:3, :3].T + T[:3, 3]
        tops.append(float(v[:, 2].max()))
    return max(tops) if tops else None


def marker_picture(dictionary: str, marker_id: int, color: tuple[int, int, int]) -> np.ndarray:
    """The marker as the virtual camera paints it, (cells * CELL_PX, cells * CELL_PX, 3) uint8 RGB,
    row 0 its top edge (+y): white cells ``color``, black ones ``color`` times ``MARKER_DARK``."""
    from ejsrl.vision.markers import marker_bits
    from ejsrl.world.rendering import MARKER_DARK

    bits = np.repeat(np.repeat(marker_bits(dictionary, marker_id), CELL_PX, axis=0), CELL_PX, axis=1)
    rgb = np.asarray(color, dtype=float).reshape(1, 1, 3)
    return np.where(bits[..., None], rgb * MARKER_DARK, rgb).round().clip(0, 255).astype(np.uint8)


def add_marker_face(scene: Any, path: str, key: tuple) -> Any:
    """The image node at ``path`` (a child of the node's frame) for the ``key`` of :func:`marker_face_key`."""
    dictionary, marker_id, side, top, color = key
    picture = marker_picture(dictionary, marker_id, color)
    # viser shows an image's row 0 towards the node's -y (its plane is turned half a turn about x,
    # as a camera's picture is): sent upside down, the marker's top row is towards +y, as captured
    return scene.add_image(path, np.ascontiguousarray(picture[::-1]), render_width=side, render_height=side, format="png",
                           position=(0.0, 0.0, top + max(1e-4, 1e-3 * side)), cast_shadow=False)
