"""Lines of the 3D view drawn in the same browser frame as the solids beside them.

viser's client applies a node's pose (``SetPositionMessage``, ``SetOrientationMessage``) to its
three.js object in the animation frame that receives it, but a line's new ``points`` go
through a React re-render that commits after that frame is drawn: they show one browser frame
later. A pendulum's rod sent as points therefore trailed its bob (a pose) while playing: median
3-8 px, up to 19-37 px at 30 frames/s in the browser tests' set-ups (1280x800, square-on). So a line is moved by poses wherever
its shape allows, and its points are sent only when its shape changes:

- a line of two distinct points (a rod, a spring drawn straight, a beam) is two *pieces*, each a
  segment of a fixed length ``h`` posed at one end and pointing at the other: together they
  cover the segment exactly while its length ``l`` stays within ``[h, 2h]``, so it stretches,
  shrinks, turns and moves by poses alone (``h = l / 1.5`` when made: a third shorter or
  longer); a length leaving that band sends new pieces, in the pieces' current frames, that
  cover every length seen so far when the longest is at most twice the shortest (a spring
  oscillating within that is then sent by poses alone), else with room the way it went; a
  one-piece line of two points that stretches becomes two pieces (drawn anew once);
- any other line is one segment set whose rigid motion (every distance kept: a turning
  polygon, a link drawn as a polyline) is fitted to the points last sent by Kabsch's method
  and sent as the pose of its geometry; a new shape (a growing trail, a chain of springs)
  sends its points, in the frame the geometry is posed in, and shows a frame later.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ejsrl.robotics.transforms import r2q
from ejsrl.view._wire import set_position, set_prop, set_wxyz

__all__ = ["RIGID_LINES", "LineDraw", "rigid_fit", "polyline_segments"]

#: lines moved by poses (see above); False sends a line's points every time, as viser's own
#: path does (the browser tests measure both)
RIGID_LINES = True

#: a two-point line's pieces are ``length / PIECE_RATIO`` long when made: it may then shrink
#: to 2/3 or stretch to 4/3 of that length (a spring about its rest length) before its points
#: are sent again
PIECE_RATIO = 1.5


def polyline_segments(points: Any) -> np.ndarray:
    """The segments (N - 1, 2, 3) float32 of a polyline through ``points`` (N, 3); one
    degenerate segment for fewer than 2 points (viser needs one)."""
    p = np.asarray(points, dtype=np.float32).reshape(-1, 3)
    if len(p) < 2:
        return np.zeros((1, 2, 3), dtype=np.float32)
    return np.ascontiguousarray(np.stack([p[:-1], p[1:]], axis=1))


def rigid_fit(ref: np.ndarray, pts: np.ndarray) -> np.ndarray | None:
    """The rigid motion (4, 4) that takes the points ``ref`` (N, 3) onto ``pts`` (N, 3), if one does.

    Kabsch's method (the rotation from the SVD of the points' cross-covariance, no
    reflection); None when the counts differ, there are fewer than 2 points, a point is
    not finite, or a point lands farther than 1e-9 m + 1e-7 of the points' extent from
    its target (the shape changed: a spring stretched, a line grew).
    """
    if ref.shape != pts.shape or len(pts) < 2 or not np.all(np.isfinite(pts)):
        return None
    ca, cb = ref.mean(axis=0), pts.mean(axis=0)
    a, b = ref - ca, pts - cb
    u, _s, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    R = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    extent = float(np.abs(b).max()) if b.size else 0.0
    if float(np.abs(a @ R.T - b).max()) > 1e-9 + 1e-7 * extent:
        return None
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = cb - R @ ca
    return T


def _turn(u: np.ndarray, d: np.ndarray) -> np.ndarray:
    """The smallest rotation (3, 3) that takes the unit vector ``u`` onto the unit vector ``d``."""
    v = np.cross(u, d)
    c = float(np.dot(u, d))
    if c < -1.0 + 1e-12:  # opposite: half a turn about any axis across u
        axis = np.cross(u, [1.0, 0.0, 0.0])
        if np.linalg.norm(axis) < 1e-6:
            axis = np.cross(u, [0.0, 1.0, 0.0])
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


def _two_points(node: Any, pts: np.ndarray) -> bool:
    """Whether a line is drawn as two pieces: a ``line`` of two distinct finite points."""
    return bool(RIGID_LINES and node.kind == "line" and len(pts) == 2 and np.all(np.isfinite(pts))
                and np.linalg.norm(pts[1] - pts[0]) > 1e-12)


class _Handle:
    """One segment set: its viser handle, the points (N, 3) it was last sent in its own frame,
    and its pose (4, 4) in the node frame."""

    __slots__ = ("h", "local", "T")

    def __init__(self, h: Any, local: np.ndarray) -> None:
        self.h = h
        self.local = local
        self.T = np.eye(4)

    def pose(self, T: np.ndarray) -> None:
        if not np.array_equal(T[:3, 3], self.T[:3, 3]):
            set_position(self.h, T[:3, 3])
        if not np.array_equal(T[:3, :3], self.T[:3, :3]):
            set_wxyz(self.h, r2q(T))
        self.T = T

    def points(self, pts: np.ndarray) -> None:
        """Send ``pts`` (N, 3, node frame) as new points, in the frame the handle is posed in."""
        self.local = (pts - self.T[:3, 3]) @ self.T[:3, :3]
        set_prop(self.h, "points", polyline_segments(self.local))


class LineDraw:
    """How one line (or trail) node is drawn: one segment set, or two pieces for two points."""

    def __init__(self, handles: list[_Handle], pieces: bool, length: float = 0.0) -> None:
        self.handles = handles
        self.pieces = pieces
        #: for pieces: the shortest and longest lengths seen (metres)
        self.seen = (length, length)
        #: the style last set (colour, width, shown): set again only when it changes
        self.sent: tuple | None = None

    @property
    def geoms(self) -> list[Any]:
        return [x.h for x in self.handles]

    @classmethod
    def build(cls, scene: Any, node: Any, base: str, color: tuple[int, int, int]) -> LineDraw:
        """The handles of ``node`` below its frame (``base``: its scene path)."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        width = float(node.props["width"])
        pieces = _two_points(node, pts)
        if not pieces:
            h = scene.add_line_segments(f"{base}/g0", polyline_segments(pts), colors=color, thickness=width, thickness_units="screen")
            h.visible = len(pts) >= 2
            draw = cls([_Handle(h, pts.copy())], False)
        else:
            length = float(np.linalg.norm(pts[1] - pts[0]))
            d = (pts[1] - pts[0]) / length
            piece = length / PIECE_RATIO
            ends = [np.array([pts[0], pts[0] + piece * d]), np.array([pts[1], pts[1] - piece * d])]
            handles = []
            for i, local in enumerate(ends):
                h = scene.add_line_segments(f"{base}/g{i}", polyline_segments(local), colors=color, thickness=width,
                                            thickness_units="screen")
                handles.append(_Handle(h, local))
            draw = cls(handles, True, length)
        draw.sent = (tuple(color), width, len(pts) >= 2)
        return draw

    def update(self, node: Any, color: tuple[int, int, int]) -> bool:
        """Send what changed of ``node``; False if it needs new handles (its kind of drawing changed)."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        shown = len(pts) >= 2
        if self.pieces:
            if len(pts) != 2 or not np.all(np.isfinite(pts)):
                return False
            shown = self._pieces(pts)
        else:
            g = self.handles[0]
            T = rigid_fit(g.local, pts) if RIGID_LINES else None
            if T is not None:  # moved as a whole: the pose of its geometry
                g.pose(T)
            elif _two_points(node, pts):  # a segment that stretches: as pieces from now on
                return False
            else:  # a new shape: its points
                g.points(pts)
        style = (tuple(color), float(node.props["width"]), shown)
        if style != self.sent:  # a moving line changes its points or poses only: each set costs
            for x in self.handles:
                # one colour for the whole line: viser's client reads it as sRGB, as the CSS colour
                # means; per-vertex colours would be read as linear and shown washed out
                x.h.colors = np.array(color, dtype=np.uint8)
                x.h.thickness = style[1]
                x.h.visible = style[2]
            self.sent = style
        return True

    def _pieces(self, pts: np.ndarray) -> bool:
        """Place the two pieces on the segment ``pts`` (2, 3); whether it is shown (not of length 0)."""
        a, b = self.handles
        length = float(np.linalg.norm(pts[1] - pts[0]))
        if length < 1e-12:
            return False
        d = (pts[1] - pts[0]) / length
        piece = float(np.linalg.norm(a.local[1] - a.local[0]))
        lo, hi = min(self.seen[0], length), max(self.seen[1], length)
        self.seen = (lo, hi)
        if not (piece * (1.0 - 1e-9) <= length <= 2.0 * piece * (1.0 + 1e-9)):
            # out of the pieces' band: new pieces, sent in their current frames (shown a frame
            # later): for every length seen if one piece length covers them all (the middle of
            # those that do, by ratio: room both ways), else with room the way it went
            if hi <= 2.0 * lo:
                piece = math.sqrt(hi / 2.0 * lo)
            else:
                piece = 0.75 * length if length > piece else 0.55 * length
            a.points(np.array([pts[0], pts[0] + piece * d]))
            b.points(np.array([pts[1], pts[1] - piece * d]))
            return True
        for x, start, direction in ((a, pts[0], d), (b, pts[1], -d)):
            u = (x.local[1] - x.local[0]) / piece
            T = np.eye(4)
            T[:3, :3] = _turn(u, direction)
            T[:3, 3] = start - T[:3, :3] @ x.local[0]
            x.pose(T)
        return True
