"""Lines of the 3D view drawn in the same browser frame as the solids beside them.

viser's client applies a node's pose (``SetPositionMessage``, ``SetOrientationMessage``) and its
visibility to its three.js object in the animation frame that receives them, but a line's new
``points`` go through a React re-render that commits after that frame is drawn: they show one
browser frame later. A pendulum's rod sent as points therefore trailed its bob (a pose) while
playing: median 3-8 px, up to 19-37 px at 30 frames/s in the browser tests' set-ups (1280x800,
square-on); a zigzag spring's end left its plate by up to 15-17 px and a trail's head its ball
by up to 25 px. So a line is moved by poses wherever it can be, and its points are sent only
when a piece must be made anew:

- a segment whose length changes is two *pieces*, each a segment of a fixed length ``h`` posed
  at one end and pointing at the other: together they cover the segment exactly while its
  length ``l`` stays within ``[h, 2h]``, so it stretches, shrinks, turns and moves by poses
  alone (``h = l / 1.5`` when made: a third shorter or longer); a length leaving that band
  sends new pieces, in the pieces' current frames, that cover every length seen so far when
  the longest is at most twice the shortest (a spring oscillating within that is then sent by
  poses alone), else with room the way it went;
- a ``line`` of two distinct points (a rod, a spring drawn straight) is one such segment;
- a ``line`` of more points is first one segment set whose rigid motion (every distance kept:
  a turning polygon, a link drawn as a polyline) is fitted to the points last sent by Kabsch's
  method and sent as the pose of its geometry; the first time its shape changes (a zigzag
  spring that stretches, a chain of springs) it is drawn anew as pieces, two a segment, if it
  has at most ``MAX_PIECE_SEGMENTS`` segments (up to 4 messages a segment, a frame); a
  longer line keeps sending its points and shows a frame late;
- a ``trail`` is one segment set of all its points (sent as points, or as a pose while it
  moves rigidly: a point going round a circle at a steady speed) under pieces on its newest
  ``TRAIL_HEAD`` segments: the set shows its new points a frame late, but the pieces that
  cover what it does not show yet are there at once, so the trail reaches its moving point.

A line drawn anew (new nodes) shows a frame late once. Pieces of one colour overlap where a
segment is shorter than ``2h``; a line has no opacity, so the overlap does not show.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np

from ejsrl.robotics.transforms import r2q
from ejsrl.view._wire import set_position, set_prop, set_wxyz
from ejsrl.world._pieces import PIECE_RATIO, refit_piece

__all__ = ["RIGID_LINES", "MAX_PIECE_SEGMENTS", "MAX_POSED_POINTS", "TRAIL_HEAD", "LineDraw", "PointsDraw", "rigid_fit", "polyline_segments"]

#: lines moved by poses (see above); False sends a line's points every time, as viser's own
#: path does (the browser tests measure both)
RIGID_LINES = True


#: a ``line`` of at most this many segments whose shape changes is drawn as pieces (two a
#: segment, moved by poses: a zigzag spring of up to 11 coils); a longer one sends its points
#: (shown a browser frame late). Pieces cost messages: a spring of 19 segments takes ~60 a frame
#: where its points took one (bench/scene_sync.py); a long chain of springs whose masses are a
#: point cloud of more than ``MAX_POSED_POINTS`` stays as it was, points and masses in step
MAX_PIECE_SEGMENTS = 24

#: a trail's newest segments drawn as pieces over its segment set (two: the set may be two
#: updates behind when a loaded browser takes two of them in one frame)
TRAIL_HEAD = 2


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
    reflection); None when the counts differ, there are fewer than 2 points, a point (of
    either) is not finite, or a point lands farther than 1e-9 m + 1e-7 of the points' extent from
    its target (the shape changed: a spring stretched, a line grew).
    """
    if ref.shape != pts.shape or len(pts) < 2 or not np.all(np.isfinite(pts)) or not np.all(np.isfinite(ref)):
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


def _eligible(node: Any, pts: np.ndarray) -> bool:
    """Whether a ``line`` whose shape changes is drawn as pieces: 2 to ``MAX_PIECE_SEGMENTS + 1`` finite points."""
    return bool(RIGID_LINES and node.kind == "line" and 2 <= len(pts) <= MAX_PIECE_SEGMENTS + 1 and np.all(np.isfinite(pts)))


def _two_points(node: Any, pts: np.ndarray) -> bool:
    """Whether a line is drawn as pieces from the start: a ``line`` of two distinct finite points."""
    return _eligible(node, pts) and len(pts) == 2 and float(np.linalg.norm(pts[1] - pts[0])) > 1e-12


class _Handle:
    """One segment set: its viser handle, the points (N, 3) it was last sent in its own frame,
    and its pose in the node frame: ``pos`` (3,) and ``q`` (wxyz) as sent, ``T`` (4, 4) the same
    pose as a matrix (made when asked for)."""

    __slots__ = ("h", "local", "_T", "pos", "q")

    def __init__(self, h: Any, local: np.ndarray) -> None:
        self.h = h
        self.local = local
        self._T: np.ndarray | None = np.eye(4)
        self.pos: tuple[float, ...] = (0.0, 0.0, 0.0)
        self.q: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0)

    @property
    def T(self) -> np.ndarray:
        if self._T is None:
            self._T = _matrix(self.pos, self.q)
        return self._T

    def pose(self, T: np.ndarray) -> None:
        """Pose the set by ``T`` (4, 4), sending what changed."""
        current = self.T
        if not np.array_equal(T[:3, 3], current[:3, 3]):
            set_position(self.h, T[:3, 3])
        self.pos = tuple(T[:3, 3].tolist())
        if not np.array_equal(T[:3, :3], current[:3, :3]):
            q = r2q(T)
            set_wxyz(self.h, q)
            self.q = tuple(q.tolist())
        self._T = T

    def pose_q(self, pos: tuple[float, ...], q: tuple[float, ...]) -> None:
        """Pose the set at ``pos`` (3,) turned by the unit quaternion ``q`` (wxyz), sending what
        changed: the pieces' path, in plain floats (a pendulum's rod is two of these a frame)."""
        if pos != self.pos:
            set_position(self.h, pos)
            self.pos = pos
            self._T = None
        if q != self.q:
            set_wxyz(self.h, q)
            self.q = q
            self._T = None

    def points(self, pts: np.ndarray) -> None:
        """Send ``pts`` (N, 3, node frame) as new points, in the frame the handle is posed in."""
        T = self.T
        with np.errstate(invalid="ignore", over="ignore"):  # a point may be nan or inf (then so is its local one)
            self.local = (pts - T[:3, 3]) @ T[:3, :3]
        set_prop(self.h, "points", polyline_segments(self.local))


def _matrix(pos: tuple[float, ...], q: tuple[float, ...]) -> np.ndarray:
    """The pose (4, 4) at ``pos`` (3,) turned by the unit quaternion ``q`` (wxyz)."""
    w, x, y, z = q
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = pos
    return T


def _turn_q(u: tuple[float, float, float], d: tuple[float, float, float]) -> tuple[float, float, float, float]:
    """The smallest rotation that takes the unit vector ``u`` onto the unit vector ``d``, as a unit
    quaternion (wxyz, w >= 0), in plain floats (Rodrigues' rotation about ``u x d``)."""
    c = u[0] * d[0] + u[1] * d[1] + u[2] * d[2]
    if c < -1.0 + 1e-12:  # opposite: half a turn about an axis across u (u x x, or u x y when u is along x)
        ax, ay, az = 0.0, u[2], -u[1]  # u x (1, 0, 0)
        if math.sqrt(ay * ay + az * az) < 1e-6:
            ax, ay, az = -u[2], 0.0, u[0]  # u x (0, 1, 0)
        n = math.sqrt(ax * ax + ay * ay + az * az)
        return (0.0, ax / n, ay / n, az / n)
    w = 1.0 + c
    x, y, z = u[1] * d[2] - u[2] * d[1], u[2] * d[0] - u[0] * d[2], u[0] * d[1] - u[1] * d[0]
    n = math.sqrt(w * w + x * x + y * y + z * z)
    return (w / n, x / n, y / n, z / n)


def _rotate(q: tuple[float, ...], v: list[float]) -> tuple[float, float, float]:
    """The vector ``v`` (3,) turned by the unit quaternion ``q`` (wxyz)."""
    w, x, y, z = q
    tx, ty, tz = 2.0 * (y * v[2] - z * v[1]), 2.0 * (z * v[0] - x * v[2]), 2.0 * (x * v[1] - y * v[0])
    return (v[0] + w * tx + (y * tz - z * ty), v[1] + w * ty + (z * tx - x * tz), v[2] + w * tz + (x * ty - y * tx))


class _Pieces:
    """One segment drawn as two pieces (see the module's docstring): ``a`` from its start, ``b``
    from its end; ``seen``: the shortest and longest lengths it has had (metres); ``shown``:
    False while the segment has no length (or no points)."""

    __slots__ = ("a", "b", "seen", "shown")

    def __init__(self, a: _Handle, b: _Handle, length: float) -> None:
        self.a, self.b = a, b
        self.seen = (length, length)
        self.shown = True

    @classmethod
    def make(cls, add: Any, p0: np.ndarray, p1: np.ndarray) -> _Pieces:
        """Pieces on the segment ``p0``-``p1`` (3,); ``add(local (2, 3))`` makes a segment set's handle."""
        length = float(np.linalg.norm(p1 - p0)) if np.all(np.isfinite([p0, p1])) else 0.0
        d = (p1 - p0) / length if length > 1e-12 else np.array([1.0, 0.0, 0.0])
        placeholder = length <= 1e-12  # hidden until the segment has a length
        if placeholder:
            p0, length = np.zeros(3), 1.0
        piece = length / PIECE_RATIO
        a, b = np.array([p0, p0 + piece * d]), np.array([p0 + length * d, p0 + (length - piece) * d])
        made = cls(_Handle(add(a), a), _Handle(add(b), b), length)
        if placeholder:
            made.seen = (math.inf, 0.0)
        return made

    @property
    def handles(self) -> tuple[_Handle, _Handle]:
        return self.a, self.b

    def place(self, p0: list[float], p1: list[float]) -> bool:
        """Cover the segment ``p0``-``p1`` (3,) with the pieces; whether it is shown (finite, of a
        length). Plain float arithmetic: every frame of a swinging rod comes here."""
        a, b = self.a, self.b
        dx, dy, dz = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if not (math.isfinite(length) and length > 1e-12):
            return False
        d = (dx / length, dy / length, dz / length)
        la = a.local.tolist()
        piece = math.dist(la[1], la[0])
        new, self.seen = refit_piece(piece, length, self.seen)
        if new is not None:  # out of the pieces' band: new pieces, sent in their current frames (shown a frame later)
            s0, s1, dv = np.array(p0, dtype=float), np.array(p1, dtype=float), np.array(d)
            a.points(np.array([s0, s0 + new * dv]))
            b.points(np.array([s1, s1 - new * dv]))
            return True
        for x, local, start, direction in ((a, la, p0, d), (b, b.local.tolist(), p1, (-d[0], -d[1], -d[2]))):
            u = ((local[1][0] - local[0][0]) / piece, (local[1][1] - local[0][1]) / piece, (local[1][2] - local[0][2]) / piece)
            q = _turn_q(u, direction)
            r = _rotate(q, local[0])
            x.pose_q((float(start[0]) - r[0], float(start[1]) - r[1], float(start[2]) - r[2]), q)
        return True

    def show(self, shown: bool, style_shown: bool) -> None:
        """Show or hide the pieces (a visibility change reaches the screen with the poses)."""
        if shown != self.shown:
            self.shown = shown
            for x in self.handles:
                x.h.visible = shown and style_shown


class _Draw:
    """What a line or a point cloud node was last sent: its handles, its style (set again only
    when it changes) and, when :meth:`update` returned False, whether to draw it anew as pieces
    (or posed points): ``changing``."""

    def __init__(self, handles: list[_Handle]) -> None:
        self.handles = handles
        self.sent: tuple | None = None
        self.changing = False


class LineDraw(_Draw):
    """How one line (or trail) node is drawn: a segment set (``handles``: none or one) and pieces;
    its style is (colour, width, shown)."""

    def __init__(self, handles: list[_Handle], pieces: list[_Pieces], kind: str) -> None:
        super().__init__(handles)
        self.pieces = pieces
        self.kind = kind

    @property
    def geoms(self) -> list[Any]:
        return [x.h for x in self.handles] + [x.h for p in self.pieces for x in p.handles]

    @classmethod
    def build(cls, scene: Any, node: Any, base: str, color: tuple[int, int, int], *, changing: bool = False) -> LineDraw:
        """The handles of ``node`` below its frame (``base``: its scene path); ``changing``: its
        shape has changed before (a line drawn anew): pieces if it has few enough segments."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        width = float(node.props["width"])
        count = itertools.count()

        def add(local: np.ndarray) -> Any:
            return scene.add_line_segments(f"{base}/g{next(count)}", polyline_segments(local), colors=color, thickness=width,
                                           thickness_units="screen")

        handles: list[_Handle] = []
        pieces: list[_Pieces] = []
        if _two_points(node, pts) or (changing and _eligible(node, pts)):
            pieces = [_Pieces.make(add, pts[i], pts[i + 1]) for i in range(len(pts) - 1)]
        else:
            handles = [_Handle(add(pts), pts.copy())]
            if node.kind == "trail" and RIGID_LINES:
                pieces = [_Pieces.make(add, np.zeros(3), np.zeros(3)) for _ in range(TRAIL_HEAD)]
        draw = cls(handles, pieces, node.kind)
        draw.sent = (tuple(color), width, len(pts) >= 2)
        for x in handles:
            x.h.visible = len(pts) >= 2
        draw._place_pieces(pts, True)
        return draw

    def update(self, node: Any, color: tuple[int, int, int]) -> bool:
        """Send what changed of ``node``; False if it needs new handles (its kind of drawing changed:
        then ``changing`` says whether to draw it anew as pieces)."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        shown = len(pts) >= 2
        style = (tuple(color), float(node.props["width"]), shown)
        if self.pieces and not self.handles:  # a line drawn as pieces
            if len(pts) != len(self.pieces) + 1 or not np.all(np.isfinite(pts)):
                self.changing = True
                return False
        elif self.handles:
            g = self.handles[0]
            T = rigid_fit(g.local, pts) if RIGID_LINES else None
            if T is not None:  # moved as a whole: the pose of its geometry
                g.pose(T)
            elif self.kind == "line" and _eligible(node, pts):  # its shape changed: as pieces from now on
                self.changing = True
                return False
            else:  # a new shape: its points
                g.points(pts)
        if style != self.sent:  # a moving line changes its points or poses only: each set costs
            for x in self.handles:
                self._style(x, style, style[2])
            for p in self.pieces:
                for x in p.handles:
                    self._style(x, style, style[2] and p.shown)
            self.sent = style
        self._place_pieces(pts, style[2])
        return True

    @staticmethod
    def _style(x: _Handle, style: tuple, visible: bool) -> None:
        # one colour for the whole line: viser's client reads it as sRGB, as the CSS colour
        # means; per-vertex colours would be read as linear and shown washed out
        x.h.colors = np.array(style[0], dtype=np.uint8)
        x.h.thickness = style[1]
        x.h.visible = visible

    def _place_pieces(self, pts: np.ndarray, style_shown: bool) -> None:
        """Put the pieces on their segments: every segment of a line drawn as pieces, or a
        trail's newest ``TRAIL_HEAD`` (the oldest piece on the oldest of them)."""
        if not self.pieces:
            return
        first = 0 if not self.handles else len(pts) - 1 - len(self.pieces)
        rows = pts[max(first, 0) : first + len(self.pieces) + 1].tolist()  # plain floats: see _Pieces.place
        for i, p in enumerate(self.pieces):
            k = first + i
            ok = 0 <= k and k + 1 < len(pts) and p.place(rows[k - max(first, 0)], rows[k + 1 - max(first, 0)])
            p.show(ok, style_shown)


#: a point cloud of at most this many points whose points move apart (the masses of a chain of
#: springs) is drawn anew as one posed point each, so that it keeps step with the lines drawn as
#: pieces beside it; a larger one sends its points (shown a browser frame late)
MAX_POSED_POINTS = 24


class PointsDraw(_Draw):
    """How one point cloud node is drawn: one cloud (moved by a pose while it moves as a whole,
    else sent its points), or one posed single-point cloud per point once its points have moved
    apart, if it has at most ``MAX_POSED_POINTS``; its style is (colour, size, count)."""

    def __init__(self, handles: list[_Handle], posed: bool) -> None:
        super().__init__(handles)
        self.posed = posed

    @property
    def geoms(self) -> list[Any]:
        return [x.h for x in self.handles]

    @classmethod
    def build(cls, scene: Any, node: Any, base: str, color: tuple[int, int, int], *, changing: bool = False) -> PointsDraw:
        """The handles of ``node`` below its frame (``base``: its scene path); ``changing``: its
        points have moved apart before: one posed point each if there are few enough."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        size = float(node.props["size"])
        if changing and RIGID_LINES and 1 <= len(pts) <= MAX_POSED_POINTS:
            handles = []
            for i, p in enumerate(pts):
                h = scene.add_point_cloud(f"{base}/g{i}", points=np.zeros((1, 3), dtype=np.float32), colors=color,
                                          point_size=size, precision="float32")
                x = _Handle(h, np.zeros((1, 3)))
                handles.append(x)
                x.h.visible = _place_point(x, p)
            draw = cls(handles, True)
        else:
            h = scene.add_point_cloud(f"{base}/g0", points=pts.astype(np.float32), colors=color, point_size=size, precision="float32")
            draw = cls([_Handle(h, pts.copy())], False)
        draw.sent = (tuple(color), size, len(pts))
        return draw

    def update(self, node: Any, color: tuple[int, int, int]) -> bool:
        """Send what changed of ``node``; False if it needs new handles (then ``changing`` says
        whether to draw it anew as posed points)."""
        pts = np.asarray(node.props["points"], dtype=float).reshape(-1, 3)
        style = (tuple(color), float(node.props["size"]), len(pts))
        if self.posed:
            if len(pts) != len(self.handles):
                self.changing = True
                return False
            for x, p in zip(self.handles, pts):
                shown = _place_point(x, p)
                if shown != x.h.visible:
                    x.h.visible = shown
        else:
            g = self.handles[0]
            T = rigid_fit(g.local, pts) if RIGID_LINES else None
            if T is not None:
                g.pose(T)
            elif RIGID_LINES and 1 <= len(pts) <= MAX_POSED_POINTS and len(pts) == len(g.local) and np.all(np.isfinite(pts)):
                self.changing = True  # its points moved apart: one posed point each from now on
                return False
            else:
                with np.errstate(invalid="ignore", over="ignore"):
                    g.local = (pts - g.T[:3, 3]) @ g.T[:3, :3]
                set_prop(g.h, "points", g.local.astype(np.float32))
        if style != self.sent:
            for x in self.handles:
                n = len(x.h.points)
                x.h.colors = np.broadcast_to(np.array(style[0], dtype=np.uint8), (n, 3)).copy()
                x.h.point_size = style[1]
            self.sent = style
        return True


def _place_point(x: _Handle, p: np.ndarray) -> bool:
    """Pose the single-point cloud ``x`` at ``p`` (3,); whether it is shown (``p`` finite)."""
    if not np.all(np.isfinite(p)):
        return False
    T = x.T.copy()
    T[:3, 3] = p
    x.pose(T)
    return True
