"""The ``drawing`` element's binding: a frame of the 2D panel from the model every display
frame, and the model changed by drags and keys.

:class:`DrawingBinding` owns one :class:`~ejsrl.view._panel2d.Panel2D`. :meth:`refresh`
(the caller holds the app lock) evaluates every child's properties and sends the frame if
it changed. Events from the browser (already checked by the panel) are applied as a
control's change is: under the app lock, the bound variables written (constrained and
clamped), then ``on_drag``/``on_release`` or the key's action, then the fixed relations.
"""

from __future__ import annotations

import base64
import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.view._drawing_mobile import MOBILE_SHAPE_KINDS, mobile_items
from ejsrl.view._panel2d import Panel2D, encode_xy
from ejsrl.view.elements import Dynamic
from ejsrl.view.elements2d import Drawing, SceneKeys, Shape2D

__all__ = ["DrawingBinding", "SceneKeysBinding", "run_key", "nice_ticks", "spring_points", "css_color", "KEY_OF_BROWSER"]

log = logging.getLogger("ejsrl.view")

#: the browser's name of a key -> its name in ``keys:`` (the rest are the same)
KEY_OF_BROWSER = {" ": "Space"}
#: the largest |world coordinate| a drag may write
MAX_ABS = 1e9


def css_color(value: Any, default: str | None) -> str | None:
    """A CSS colour for the canvas: a colour name or '#rrggbb' as given, an RGB triple (0-1) as rgb()."""
    if value is None:
        return default
    if isinstance(value, str):
        return value[:64]
    try:
        from ejsrl.world.colors import to_rgb

        r, g, b = to_rgb(value)
    except Exception:  # noqa: BLE001 - not a colour: the default
        return default
    return f"rgb({int(round(255 * r))},{int(round(255 * g))},{int(round(255 * b))})"


def nice_ticks(lo: float, hi: float, target: int = 6) -> list[float]:
    """Round tick values (1, 2, 5 x 10^k steps) covering ``[lo, hi]``, about ``target`` of them."""
    span = hi - lo
    if not (math.isfinite(lo) and math.isfinite(hi)) or span <= 0:
        return []
    raw = span / max(1, target)
    mag = 10.0 ** math.floor(math.log10(raw))
    step = next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw)
    first = math.ceil(lo / step - 1e-9)
    last = math.floor(hi / step + 1e-9)
    return [round(k * step, 12) for k in range(int(first), int(last) + 1)]


def _tick_label(v: float, step: float) -> str:
    decimals = max(0, -int(math.floor(math.log10(step)))) if step > 0 else 0
    text = f"{v:.{decimals}f}"
    return "0" if float(text) == 0 else text.replace("-", "\u2212")


def spring_points(a: np.ndarray, b: np.ndarray, coils: int, radius: float) -> np.ndarray:
    """The zig-zag of a spring from ``a`` to ``b`` ((2,) world points): (2 coils + 3, 2) points,
    straight for a tenth of the length at each end, ``radius`` (world units) to each side."""
    d = b - a
    length = float(np.hypot(*d))
    if length == 0 or not math.isfinite(length):
        return np.array([a, b], dtype=float)
    u = d / length
    n = np.array([-u[1], u[0]])
    k = 2 * int(coils)
    s = 0.1 + 0.8 * (np.arange(k) + 0.5) / k
    side = np.where(np.arange(k) % 2 == 0, 1.0, -1.0) * radius
    mids = a + np.outer(s, d) + np.outer(side, n)
    return np.vstack([a, a + 0.1 * d, mids, a + 0.9 * d, b])


def _xy(value: Any, what: str) -> np.ndarray:
    """[x, y] or (N, 2) -> an (N, 2) float array; a clear error otherwise."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 1 and a.shape[0] == 2:
        return a.reshape(1, 2)
    if a.ndim == 2 and a.shape[1] == 2:
        return a
    if a.ndim == 2 and a.shape[0] == 2 and a.shape[1] != 2:
        raise ValueError(f"{what} must be [x, y] or an N x 2 array, but has shape {a.shape} (a 2 x N array: transpose it, .T)")
    raise ValueError(f"{what} must be [x, y] or an N x 2 array, but has shape {a.shape}")


def _png_data_url(img: Any) -> str:
    """An (H, W) or (H, W, 3|4) image as a PNG data URL (written with zlib, not OpenCV: the
    same in a web page, whose Python has no OpenCV)."""
    from ejsrl.view._plots import prepare_image
    from ejsrl.web._png import encode_png

    rgb = prepare_image(img)
    if rgb is None:
        raise ValueError(f"an image must be an H x W or H x W x 3 array, got shape {np.shape(img)}")
    return "data:image/png;base64," + base64.b64encode(encode_png(rgb)).decode("ascii")


class _ShapeState:
    """What a child keeps between frames: a trace's points (and the independent variable's value
    at the last one: when it goes back, the trace starts again), an image's encoding."""

    def __init__(self) -> None:
        self.trace: list[tuple[float, float]] = []
        self.time: float | None = None
        self.image_key: Any = None
        self.image_url: str | None = None
        #: the revision of ``clear_trace`` requests last applied (``ejsrl.sim._traces``)
        self.cleared = 0


def _error_note(error: Any) -> str:
    """The text written on a panel while the lab shows ``error`` (a ``UserCodeError``): where and what, cut to 300 characters."""
    where = getattr(error, "where", "") or ""
    text = f"\u26a0 {where}: {getattr(error, 'message', error)}" if where else f"\u26a0 {getattr(error, 'message', error)}"
    return text if len(text) <= 300 else text[:299] + "\u2026"


class DrawingBinding:
    """One ``Drawing`` element shown by a :class:`Panel2D` in ``gui``; ``app``: the running app
    (``lock``, ``model``, ``safe_value``, ``guard``, ``fail``, ``_after_change``, ``_wake``)."""

    def __init__(self, gui: Any, drawing: Drawing, app: Any, *, key: str, clock: Callable[[], float] | None = None) -> None:
        self.drawing = drawing
        self.app = app
        kw = {"clock": clock} if clock is not None else {}
        keys = [" " if k == "Space" else k for k in drawing.keys]  # the others scroll the page, as ever
        auto = drawing.height is None and drawing.aspect == "equal"  # as high as the ranges need (the client sizes it)
        height = drawing.height if drawing.height is not None else 300
        self.panel = Panel2D(gui, key, height=height, on_event=self.on_event, keys=keys, auto_height=auto, **kw)
        self.shapes: dict[str, Shape2D] = {s.name: s for s in drawing.children}
        self.states: dict[str, _ShapeState] = {s.name: _ShapeState() for s in drawing.children}
        self.base_dir = getattr(app, "base_dir", None)
        from ejsrl.sim._traces import trace_clears

        #: the app's ``clear_trace`` requests (spec code's); a wrong name is refused there
        self.trace_clears = trace_clears(app)
        self.trace_clears.register(s.name for s in drawing.children if s.kind == "trace")
        for name, st in self.states.items():
            st.cleared = self.trace_clears.revision(name)
        #: the frame last built (tests read it)
        self.frame: dict[str, Any] | None = None

    # -- every frame ----------------------------------------------------------------------------
    def refresh(self) -> None:
        """Build this frame's picture and send it if it changed (the caller holds the app lock).

        An element whose expression fails (a set of the wrong shape, an exception) is left
        out of the picture, the error is recorded (the lab pauses and shows it) and the
        other elements are drawn, with the error written on the panel. While the lab shows
        an error the panel keeps its last picture, the error written on it.
        """
        app = self.app
        if app.error is not None and self.frame is not None:
            note = _error_note(app.error)
            if self.frame.get("error") != note:
                self.frame = dict(self.frame, error=note)
                self.panel.show(self.frame)
            return
        frame = self.build()
        if frame is not None:
            self.frame = frame
            self.panel.show(frame)

    def clear(self) -> None:
        """Forget the traces (on reset)."""
        for st in self.states.values():
            st.trace.clear()

    def _time(self) -> float | None:
        """The model's independent variable now (None if it has none)."""
        model = self.app.model
        name = getattr(model, "INDEPENDENT", None)
        try:
            return float(getattr(model, name)) if name else None
        except (TypeError, ValueError, AttributeError):
            return None

    def _value(self, prop: Any, where: str) -> Any:
        """A property's value now; raises what its expression raises (the caller records it)."""
        return prop(self.app.model) if isinstance(prop, Dynamic) else prop

    def build(self) -> dict[str, Any] | None:
        """The frame of the panel now, or None when its ranges cannot be had (the error recorded).

        An element that fails is left out and its error recorded (the first one, if the lab
        shows none yet); the frame then carries ``error``, the text written on the panel.
        """
        d, app = self.drawing, self.app
        try:
            xr = self._value(d.x_range, d.where)
            yr = self._value(d.y_range, d.where)
            x0, x1 = (float(v) for v in np.asarray(xr, dtype=float).reshape(2))
            y0, y1 = (float(v) for v in np.asarray(yr, dtype=float).reshape(2))
        except Exception as exc:  # noqa: BLE001 - user code may raise anything
            if app.error is None:
                app.fail(ValueError(f"x_range and y_range must be [min, max] ({exc})") if isinstance(exc, (TypeError, ValueError)) else exc, d.where)
            return None
        if not (x1 > x0 and y1 > y0):
            if app.error is None:
                app.fail(ValueError(f"x_range and y_range must be [min, max] with min < max (got x {x0:g}..{x1:g}, y {y0:g}..{y1:g})"), d.where)
            return None
        try:
            title = self._value(d.title, d.where) if isinstance(d.title, Dynamic) else d.title
        except Exception as exc:  # noqa: BLE001
            title = ""
            if app.error is None:
                app.fail(exc, d.where)
        items: list[dict[str, Any]] = []
        bounds = (x0, x1, y0, y1)
        for shape in d.children:
            try:
                vis = self._value(shape.visible, shape.where)
                if vis is None or not bool(vis):
                    continue
                item = self._item(shape, bounds)
            except Exception as exc:  # noqa: BLE001 - the others are still drawn
                if app.error is None:
                    app.fail(exc, shape.where)
                continue
            if isinstance(item, list):  # a mobile kind: several items
                items.extend(item)
            elif item is not None:
                items.append(item)
        frame: dict[str, Any] = {
            "bounds": [x0, x1, y0, y1],
            "aspect": d.aspect,
            "background": d.background or None,
            "title": "" if title is None else str(title),
            "axes": self._axes(bounds) if (d.axes or d.grid) else None,
            "legend": [],
            "items": items,
        }
        if app.error is not None:
            frame["error"] = _error_note(app.error)
        return frame

    def _axes(self, bounds: tuple[float, float, float, float]) -> dict[str, Any]:
        """Ticks over three times the window each way (the client shows those inside the window it grows to)."""
        d = self.drawing
        out: dict[str, Any] = {"grid": bool(d.grid)}
        for axis, lo, hi, title in (("x", bounds[0], bounds[1], d.x_label), ("y", bounds[2], bounds[3], d.y_label)):
            span = hi - lo
            ticks = nice_ticks(lo, hi)
            step = ticks[1] - ticks[0] if len(ticks) > 1 else span
            wide = nice_ticks(lo - 3 * span, hi + 3 * span, target=int(round(7 * span / step)) if step > 0 else 42)
            out[axis] = {"title": title or "", "log": False, "ticks": [[v, _tick_label(v, step)] for v in wide]}
        if not d.axes:  # a grid alone: lines, no frame labels
            for axis in ("x", "y"):
                out[axis]["ticks"] = [[v, ""] for v, _ in out[axis]["ticks"]]
        return out

    def _item(self, s: Shape2D, bounds: tuple[float, float, float, float]) -> dict[str, Any] | None:
        """One frame item of ``s`` (None if a value is missing after an error)."""
        p: dict[str, Any] = {}
        for key, prop in s.props.items():
            v = self._value(prop, s.where)
            if v is None and prop is not None:
                return None
            p[key] = v
        color = css_color(self._value(s.color, s.where) if isinstance(s.color, Dynamic) else s.color, None)
        kind = s.kind
        item: dict[str, Any]
        if kind == "point":
            xy = _xy(p["position"], f"the position of {s.name}")
            item = {"t": "markers", "xy": encode_xy(xy), "shape": p.get("shape", "circle"), "size": float(p.get("size", 8)),
                    "fill": color or "#1c7ed6", "stroke": None}
        elif kind == "particle":
            xy = _xy(p["position"], f"the position of {s.name}")
            item = {"t": "circles", "xy": encode_xy(xy), "r": float(p.get("radius", 0.1)), "fill": color or "#e03131",
                    "stroke": css_color(p.get("stroke"), None), "width": 1.0}
        elif kind == "circle":
            xy = _xy(p["position"], f"the position of {s.name}")
            item = {"t": "circles", "xy": encode_xy(xy), "r": float(p["radius"]), "fill": css_color(p.get("fill"), None),
                    "stroke": color or "#1c7ed6", "width": float(p.get("width", 1.5))}
        elif kind == "segment":
            a, b = np.broadcast_arrays(_xy(p["start"], f"the start of {s.name}"), _xy(p["end"], f"the end of {s.name}"))
            item = {"t": "segments", "xy": encode_xy(np.hstack([a, b])), "stroke": color or "#343a40", "width": float(p.get("width", 1.5))}
        elif kind == "arrow":
            a, v = np.broadcast_arrays(_xy(p["position"], f"the position of {s.name}"), _xy(p["vector"], f"the vector of {s.name}"))
            item = {"t": "arrows", "xy": encode_xy(np.hstack([a, v])), "stroke": color or "#1971c2", "width": float(p.get("width", 1.5)),
                    "head": float(p.get("head", 8))}
        elif kind == "spring":
            a = _xy(p["start"], f"the start of {s.name}")[0]
            b = _xy(p["end"], f"the end of {s.name}")[0]
            pts = spring_points(a, b, int(p.get("coils", 8)), float(p.get("radius", 0.1)))
            item = {"t": "polyline", "xy": encode_xy(pts), "stroke": color or "#495057", "width": float(p.get("width", 1.5)),
                    "dash": None, "closed": False, "fill": None}
        elif kind in ("polygon", "polyline"):
            pts = _xy(p["points"], f"the points of {s.name}")
            closed = kind == "polygon"
            item = {"t": "polyline", "xy": encode_xy(pts), "stroke": color or "#343a40", "width": float(p.get("width", 1.5)),
                    "dash": None, "closed": closed, "fill": css_color(p.get("fill"), None) if closed else None}
        elif kind == "trace":
            pt = _xy(p["point"], f"the point of {s.name}")[0]
            st = self.states[s.name]
            now = self._time()
            if now is not None and st.time is not None and now < st.time:
                st.trace.clear()  # the independent variable went back (a reset, a new launch): a new trace
            cleared = self.trace_clears.revision(s.name)
            if cleared != st.cleared:  # spec code called clear_trace(): a new trace from here
                st.cleared = cleared
                st.trace.clear()
            same_instant = now is not None and now == st.time and bool(st.trace)
            st.time = now
            if not np.all(np.isfinite(pt)):
                pass
            elif same_instant:
                st.trace[-1] = (float(pt[0]), float(pt[1]))  # paused, moved by a drag or a control: the point moves
            elif not st.trace or st.trace[-1] != (pt[0], pt[1]):
                st.trace.append((float(pt[0]), float(pt[1])))
                limit = int(p.get("max_points", 1000))
                if len(st.trace) > limit:
                    del st.trace[: len(st.trace) - limit]
            pts = np.array(st.trace, dtype=float).reshape(-1, 2)
            item = {"t": "polyline", "xy": encode_xy(pts), "stroke": color or "#868e96", "width": float(p.get("width", 1.5)),
                    "dash": None, "closed": False, "fill": None}
        elif kind == "text":
            pos = _xy(p["position"], f"the position of {s.name}")[0]
            item = {"t": "text", "x": float(pos[0]), "y": float(pos[1]), "text": str(p["text"]), "size": float(p.get("size", 14)),
                    "color": color or "#212529", "align": p.get("align", "center")}
        elif kind == "image":
            url = self._image(s, p)
            pos = _xy(p.get("position", (0.0, 0.0)), f"the position of {s.name}")[0]
            size = np.asarray(p.get("size", (1.0, 1.0)), dtype=float).reshape(2)
            item = {"t": "image", "x0": float(pos[0] - size[0] / 2), "y0": float(pos[1] - size[1] / 2),
                    "x1": float(pos[0] + size[0] / 2), "y1": float(pos[1] + size[1] / 2), "src": url}
        elif kind == "axes":
            x0, x1, y0, y1 = bounds
            xy = np.array([[x0, 0.0, x1 - x0, 0.0], [0.0, y0, 0.0, y1 - y0]])
            item = {"t": "arrows", "xy": encode_xy(xy), "stroke": color or "#495057", "width": float(p.get("width", 1.0)), "head": 9.0}
        elif kind == "grid":
            item = self._grid(bounds, float(p.get("spacing", 1.0)), color, float(p.get("width", 1.0)))
        elif kind in MOBILE_SHAPE_KINDS:
            items = mobile_items(kind, s.name, p, color, css_color, lambda img: self._picture(s, img))
            if s.drag is not None and items:
                items[0]["id"] = s.name
                items[0]["drag"] = {"x": "x", "y": "y"}.get(s.drag.along, "xy")
            return items  # type: ignore[return-value]
        else:  # pragma: no cover - Shape2D refuses other kinds
            return None
        if s.drag is not None:
            item["id"] = s.name
            item["drag"] = {"x": "x", "y": "y"}.get(s.drag.along, "xy")
            if s.drag.handle == "end":
                item["handle"] = "end"
        return item

    @staticmethod
    def _grid(bounds: tuple[float, float, float, float], spacing: float, color: str | None, width: float) -> dict[str, Any]:
        x0, x1, y0, y1 = bounds
        if not (math.isfinite(spacing) and spacing > 0):
            raise ValueError(f"a grid's spacing must be a positive number, got {spacing}")
        sx, sy = 3 * (x1 - x0), 3 * (y1 - y0)  # the client may grow the window (equal aspect)
        xs = np.arange(math.ceil((x0 - sx) / spacing), math.floor((x1 + sx) / spacing) + 1) * spacing
        ys = np.arange(math.ceil((y0 - sy) / spacing), math.floor((y1 + sy) / spacing) + 1) * spacing
        if len(xs) + len(ys) > 2000:
            raise ValueError(f"a grid of spacing {spacing:g} draws {len(xs) + len(ys)} lines here; make the spacing larger")
        rows = [[x, y0 - sy, x, y1 + sy] for x in xs] + [[x0 - sx, y, x1 + sx, y] for y in ys]
        return {"t": "segments", "xy": encode_xy(np.array(rows, dtype=float).reshape(-1, 4)), "stroke": color or "#e9ecef", "width": width}

    def _picture(self, s: Shape2D, img: np.ndarray) -> str:
        """An image's data URL, encoded again only when it changed."""
        st = self.states[s.name]
        key = (img.shape, hash(img.tobytes()))
        if st.image_key != key:
            st.image_key, st.image_url = key, _png_data_url(img)
        return st.image_url  # type: ignore[return-value]

    def _image(self, s: Shape2D, p: dict[str, Any]) -> str:
        st = self.states[s.name]
        if p.get("file"):
            key = ("file", p["file"])
            if st.image_key != key:
                from pathlib import Path

                from ejsrl.view._image_file import read_image_file  # OpenCV served, its decoded copy in a page

                path = Path(self.base_dir or ".") / str(p["file"])
                st.image_key, st.image_url = key, _png_data_url(read_image_file(path, str(p["file"])))
            return st.image_url  # type: ignore[return-value]
        a = np.asarray(p.get("source"))
        key = (a.shape, a.dtype.str, hash(a.tobytes()))
        if st.image_key != key:
            st.image_key, st.image_url = key, _png_data_url(a)
        return st.image_url  # type: ignore[return-value]

    # -- events from the browser ------------------------------------------------------------------
    def on_event(self, event: dict[str, Any]) -> None:
        """A checked event (see :func:`ejsrl.view._panel2d.parse_events`); no lock held."""
        if event["k"] == "drag":
            self.drag(event["id"], event["phase"], event["x"], event["y"], event.get("i", 0))
        elif event["k"] == "key" and event["phase"] == "down":
            self.key(event["key"])

    def key(self, browser_key: str) -> bool:
        """Run the action mapped to ``browser_key`` (the browser's name); True if there was one."""
        return run_key(self.app, self.drawing.keys, browser_key, self.drawing.where)

    def constrained(self, shape: Shape2D, x: float, y: float) -> tuple[float, float] | None:
        """Where the dragged point of ``shape`` goes for the pointer at (x, y) (the caller holds
        the app lock): along x, along y, on the curve, then inside the region; None if not finite."""
        drag, app = shape.drag, self.app
        assert drag is not None
        if drag.along == "curve" and drag.curve is not None:
            got = app.guard(lambda: drag.curve(app.model, x, y), shape.where)  # type: ignore[misc]
            if got is None:
                return None
            try:
                x, y = (float(v) for v in np.asarray(got, dtype=float).reshape(2))
            except (TypeError, ValueError):
                app.fail(ValueError(f"the curve of {shape.name} must return a point [x, y], got {got!r}"), shape.where)
                return None
        if drag.region is not None:
            region = app.safe_value(drag.region, shape.where)
            if region is None:
                return None
            xmin, xmax, ymin, ymax = (float(v) for v in np.asarray(region, dtype=float).reshape(4))
            x, y = min(max(x, xmin), xmax), min(max(y, ymin), ymax)
        if not (math.isfinite(x) and math.isfinite(y)) or abs(x) > MAX_ABS or abs(y) > MAX_ABS:
            return None
        return x, y

    def drag(self, name: str, phase: str, x: float, y: float, row: int = 0) -> bool:
        """Apply a drag of element ``name`` to (x, y) (world units): write the bound variables
        (constrained), run ``on_drag`` (start, move) or ``on_release``, then the fixed relations.
        Returns False if the element is not draggable (the event is dropped)."""
        shape = self.shapes.get(name)
        if shape is None or shape.drag is None:
            return False
        drag, app = shape.drag, self.app
        with app.lock:
            if app.error is not None and phase != "release":
                return False
            point = self.constrained(shape, float(x), float(y))
            if point is not None:
                self._write(shape, point, row)
            code = drag.on_release if phase == "release" else drag.on_drag
            if code is not None and app.error is None:
                app.guard(lambda: code(app.model), shape.where)
            app._after_change()
        app._wake()
        return True

    def _write(self, shape: Shape2D, point: tuple[float, float], row: int) -> None:
        drag, app, model = shape.drag, self.app, self.app.model
        assert drag is not None
        x, y = point
        if drag.set_x is None and drag.set_y is None:  # a set bound to one (N, 2) array variable
            from ejsrl.sim.paths import getter, setter

            current = app.guard(lambda: getter(drag.bind[0])(model), shape.where)
            arr = np.array(current, dtype=float, copy=True) if current is not None else None
            if arr is None or arr.ndim != 2 or arr.shape[1] != 2 or not 0 <= row < arr.shape[0]:
                app.fail(ValueError(f"dragging {shape.name}: '{drag.bind[0]}' must be an N x 2 array with a row {row}"), shape.where)
                return
            arr[row] = (x, y)
            set_it = setter(drag.bind[0])
            app.guard(lambda: set_it(model, arr), shape.where)
            remember = getattr(app, "remember_user_value", None)
            if remember is not None:
                remember(drag.bind[0], set_it, arr)
            return
        for j, (set_it, value, target) in enumerate(((drag.set_x, x, drag.bind[0]), (drag.set_y, y, drag.bind[-1]))):
            if set_it is None:
                continue
            k = min(j, len(drag.bind) - 1)  # one bound target: its limits whichever coordinate it is
            lo, hi = drag.limits[k] if k < len(drag.limits) else (None, None)
            if lo is not None:
                value = max(value, lo)
            if hi is not None:
                value = min(value, hi)
            if k < len(drag.ints) and drag.ints[k]:
                value = int(round(value))
            app.guard(lambda s=set_it, v=value: s(model, v), shape.where)
            remember = getattr(app, "remember_user_value", None)
            if remember is not None:
                remember(target, set_it, value)


def run_key(app: Any, keys: dict[str, Callable[[Any], None]], browser_key: str, where: str) -> bool:
    """Run the action ``keys`` maps ``browser_key`` (the browser's name) to, then the fixed
    relations, as a button does; True if there was one."""
    action = keys.get(KEY_OF_BROWSER.get(browser_key, browser_key))
    if action is None:
        return False
    with app.lock:
        app.guard(lambda: action(app.model), where)
        app._after_change()
    app._wake()
    return True


class SceneKeysBinding:
    """The ``keyboard`` element: keys pressed while the 3D view has the focus run their actions.
    A :class:`Panel2D` of height 0 reports them (it draws nothing)."""

    def __init__(self, gui: Any, element: SceneKeys, app: Any, *, key: str) -> None:
        self.element = element
        self.app = app
        browser_keys = [" " if k == "Space" else k for k in element.keys]  # the others stay the 3D camera's
        self.panel = Panel2D(gui, key, height=0, on_event=self.on_event, scene_keys=True, keys=browser_keys)

    def refresh(self) -> None:
        """Nothing to draw."""

    def clear(self) -> None:
        """Nothing to forget."""

    def on_event(self, event: dict[str, Any]) -> None:
        if event["k"] == "key" and event["phase"] == "down":
            run_key(self.app, self.element.keys, event["key"], self.element.where)
