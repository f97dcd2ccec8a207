"""Image elements in the control panel: a picture (a virtual camera's, a processed frame) shown
when the browser has laid its panel out, and sent again only when it changes.

viser's client mounts a new panel's elements twice while it lays the panel out (the panel
first floats, then docks: both copies are in the page for a moment); an image shown then has
its picture's ``blob:`` URL revoked while it loads, and the console logs ``Failed to load
resource: net::ERR_FILE_NOT_FOUND``. So an :class:`ImageBinding` makes its element hidden,
with a *probe* before it: an HTML element whose ``<img onerror>`` hook waits until exactly one
copy of the probe is left in the page (the panel is laid out) and then writes
:data:`LAID_OUT` into a hidden text input (the bridge the 2D panels use). The server checks
that message (exactly that string, from a client) and shows the element, then removes the
probe and the input. A timer of :data:`IMAGE_SETTLE` seconds is kept only as a fallback: a
tab whose page never reports (a background tab, a closed folder) still shows the picture.
"""

from __future__ import annotations

import html
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.view.elements import Image

__all__ = ["ImageBinding", "prepare_image", "draw_rings", "picture_of", "probe_html", "IMAGE_RATE", "IMAGE_SETTLE", "LAID_OUT"]


def prepare_image(img: Any, points: Any = None) -> np.ndarray | None:
    """An (H, W, 3) uint8 image ready for viser, with ``points`` (N, 2) (x, y) drawn over it.

    Returns None if ``img`` is not an image.
    """
    if img is None:
        return None
    a = np.asarray(img)
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    elif a.ndim == 3 and a.shape[2] == 1:
        a = np.repeat(a, 3, axis=2)
    elif a.ndim == 3 and a.shape[2] == 4:
        a = a[:, :, :3]
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        return None
    if a.dtype != np.uint8:
        if np.issubdtype(a.dtype, np.floating) and a.size and float(np.nanmax(a)) <= 1.0:
            a = np.clip(np.nan_to_num(a) * 255.0, 0, 255).astype(np.uint8)
        else:
            a = np.clip(np.nan_to_num(a.astype(np.float64)), 0, 255).astype(np.uint8)
    a = np.ascontiguousarray(a)
    if points is not None:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts):
            a = draw_rings(a.copy(), pts)
    return a


def picture_of(src: Any, pts: Any, label: str = "") -> tuple[Any, Any]:
    """An image element's ``(source, points)`` as it draws them: a vision pipeline's result
    (``vision.Pipeline(...)(img)``: anything with ``image`` and ``points``) gives its image and,
    unless the element names its own, its points; a value that is no picture (H x W, H x W x 1,
    3 or 4 numbers) raises a TypeError saying what it is, which pauses the lab with that message
    (a blank element said nothing)."""
    if src is None:
        return None, pts
    if not isinstance(src, np.ndarray) and hasattr(src, "image") and hasattr(src, "points"):
        src, pts = src.image, (src.points if pts is None else pts)
    try:
        a = np.asarray(src)
    except (TypeError, ValueError):  # ragged lists
        a = None
    ok = a is not None and a.dtype != object and (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (1, 3, 4))) and a.size > 0
    if not ok:
        if a is None or a.dtype == object or a.dtype.kind in "USO":
            what = f"a {type(src).__name__}" + (f" ({src!r:.40})" if isinstance(src, str) else "")
        elif a.ndim == 0:
            what = f"a single number ({a.item()!r})"
        else:
            what = f"an array of shape {a.shape} ({a.dtype})"
        name = f"image element '{label}'" if label else "an image element"
        raise TypeError(f"{name}: its source gives {what}, not a picture (an H x W grey or H x W x 3 colour array; "
                        "a vision pipeline's result shows as its .image)")
    return a, pts


#: the rings' colours: a red ring with a black one just outside it (seen on light and dark pictures)
_RING_RED = np.array([255.0, 40.0, 40.0], np.float32)


def draw_rings(a: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Draw a ring around each point ``(x, y)`` (pixel coordinates, sub-pixel) of ``pts`` (N, 2)
    on the (H, W, 3) uint8 image ``a``, in place: red, radius ``min(H, W) / 80`` (at least 2 px),
    2 px wide, with a black ring just outside it, anti-aliased. NumPy only (no OpenCV: a web
    page's Python draws them too); every ring at once (thousands of SUSAN corners: a few ms),
    the black rings under the red ones where rings overlap. Points not finite or far outside
    the picture are left out. Returns ``a``."""
    h, w = a.shape[:2]
    r = max(2, int(round(min(h, w) / 80)))
    keep = np.isfinite(pts).all(axis=1) & (pts[:, 0] > -w) & (pts[:, 0] < 2 * w) & (pts[:, 1] > -h) & (pts[:, 1] < 2 * h)
    pts = pts[keep]
    if not len(pts):
        return a
    reach = r + 3  # the black ring's outer edge (r + 2) and its half a pixel of anti-aliasing
    off = np.arange(-reach, reach + 1)
    cx, cy = np.round(pts[:, 0]).astype(np.int64), np.round(pts[:, 1]).astype(np.int64)
    X = cx[:, None, None] + off[None, None, :]
    Y = cy[:, None, None] + off[None, :, None]
    d = np.hypot(X - pts[:, 0, None, None], Y - pts[:, 1, None, None]).astype(np.float32)
    inside = (X >= 0) & (X < w) & (Y >= 0) & (Y < h)
    at = (Y * w + X)[inside]
    d = d[inside]
    # coverage of a 2 px wide ring of radius R at distance d: 1 within 1 px of R, fading over half a pixel
    black = np.zeros(h * w, np.float32)
    red = np.zeros(h * w, np.float32)
    np.maximum.at(black, at, np.clip(1.5 - np.abs(d - (r + 1)), 0.0, 1.0))
    np.maximum.at(red, at, np.clip(1.5 - np.abs(d - r), 0.0, 1.0))
    touched = np.flatnonzero(black + red)
    flat = a.reshape(-1, 3)
    px = flat[touched].astype(np.float32)
    kb, kr = black[touched, None], red[touched, None]
    px = px * (1.0 - kb)  # the black ring, then the red one over it
    px = px * (1.0 - kr) + _RING_RED * kr
    flat[touched] = np.clip(np.round(px), 0, 255).astype(np.uint8)
    return a


#: the most pictures a second an image element reads and sends
IMAGE_RATE = 20.0

#: seconds after which a hidden image element is shown even if its page never said that its
#: panel is laid out (a page without the probe's script; a page busy with two CPU-bound processes
#: beside it reports within ~10 s of its first visit)
IMAGE_SETTLE = 30.0

#: what the probe writes into its input once its panel is laid out: the only value accepted
LAID_OUT = "laid-out"

# The probe's hook (``this``: its <img>). It polls (50 ms) until its copy is the only one in the
# page, after the first animation frame (the panel's first layout pass has placed both copies
# by then), then writes LAID_OUT into the input whose label names data-ev, as React expects.
# Until the server takes the probe away (it does when it shows the element), it writes again
# every second, first an empty value so that React sees a change: with three or more images in a
# panel, the write of one of them now and then never reached the server (the trial's middle
# image stayed hidden for IMAGE_SETTLE seconds); the server ignores anything but LAID_OUT.
_PROBE_HOOK = (
    "(function(img){var id=img.getAttribute('data-ejs-image'),ev=img.getAttribute('data-ev'),n=0;"
    "function field(){var w=document.querySelector('label[for=\"'+ev+'\"]');"
    "for(var i=0;w&&i<6&&!(w.querySelector&&w.querySelector('input'));i++)w=w.parentElement;"
    "return w?w.querySelector('input'):null}"
    "function put(f,v){Object.getOwnPropertyDescriptor(HTMLInputElement.prototype,'value').set.call(f,v);"
    "f.dispatchEvent(new Event('input',{bubbles:true}))}"
    "function check(){if(!img.isConnected)return;var f=field();"
    "if(!f||document.querySelectorAll('img[data-ejs-image=\"'+id+'\"]').length!==1){setTimeout(check,50);return}"
    "if(n>0)put(f,'');put(f,'" + LAID_OUT + "');if(++n<30)setTimeout(check,1000)}"
    "requestAnimationFrame(function(){setTimeout(check,50)})})(this)"
)


def probe_html(probe_id: str, input_uuid: str) -> str:
    """The probe's HTML: a style that hides the input ``input_uuid`` and a hidden ``<img>``
    whose hook reports (see :data:`_PROBE_HOOK`); ``probe_id`` names the image element."""
    hide = f'div:has(> div > div > p > label[for="{html.escape(input_uuid)}"]){{display:none!important}}'
    return (
        f"<style>{hide}</style>"
        f'<img alt="" style="display:none" src="data:," data-ejs-image="{html.escape(probe_id)}" '
        f'data-ev="{html.escape(input_uuid)}" onerror="{html.escape(_PROBE_HOOK, quote=True)}">'
    )


class ImageBinding:
    """One ``Image`` element: sends the picture only when the source or the points changed.

    ``first()``: the source and points now, ``(src, pts)``, read once to make the element
    with the lab's first picture (a grey placeholder if it gives none). The element is shown
    when its page says that its panel is laid out (:data:`LAID_OUT`, see the module's
    docstring), or else :data:`IMAGE_SETTLE` seconds after it is made (by a timer, or the first
    :meth:`update` then, whichever comes first: a paused lab is not refreshed); pictures are
    sent from then on, at most ``max_rate`` a second.
    """

    def __init__(
        self, gui: Any, image: Image, *, label: str | None = None, max_rate: float = IMAGE_RATE, clock: Callable[[], float] = time.monotonic,
        first: Callable[[], tuple[Any, Any]] | None = None,
    ) -> None:
        self.image = image
        self.max_rate = max_rate
        self.clock = clock
        self._last_src: np.ndarray | None = None
        self._last_pts: np.ndarray | None = None
        #: shown (and sent pictures) from this time on at the latest
        self._show_at = clock() + IMAGE_SETTLE
        self._shown = False
        #: what showed the element: "page" (its probe's message), "timer" (the fallback), None (hidden)
        self.shown_by: str | None = None
        #: messages on the probe's input that were not :data:`LAID_OUT` from a client (ignored)
        self.refused = 0
        self._last_push = -math.inf
        #: when a source was last looked at (sent or not): read again at most max_rate a second
        self._last_read = -math.inf
        self.pushes = 0
        shown = None
        if first is not None:
            src, pts = first()
            if src is not None:
                a, p = np.asarray(src), None if pts is None else np.asarray(pts, dtype=float)
                shown = prepare_image(a, p)
                if shown is not None:
                    self._last_src, self._last_pts = a.copy(), None if p is None else p.copy()
        placeholder = np.full((2, 2, 3), 40, dtype=np.uint8) if shown is None else shown
        label = str(image.label or "") if label is None else label
        self._reveal_lock = threading.Lock()
        # the input first: the probe names its uuid (its hook writes it, its style hides it)
        self._signal = gui.add_text("ejs image laid out", "")
        uuid = self._signal._impl.uuid
        self._probe = gui.add_html(probe_html(f"image-{uuid[:12]}", uuid))
        self.handle = gui.add_image(placeholder, label=label or None, format="jpeg", jpeg_quality=85, visible=False)
        self._signal.on_update(self._on_signal)
        self._timer: threading.Timer | None = threading.Timer(IMAGE_SETTLE, self._reveal, kwargs={"by": "timer"})
        self._timer.daemon = True
        try:
            self._timer.start()
        except RuntimeError:  # no threads (a web page's Python): update() shows it once IMAGE_SETTLE is past
            self._timer = None

    def _on_signal(self, event: Any) -> None:
        """viser's callback for the probe's input: show the element if a client wrote exactly
        :data:`LAID_OUT` (anything else is counted in :attr:`refused` and ignored)."""
        value = getattr(self._signal, "value", None)
        if getattr(event, "client", None) is None or not isinstance(value, str) or value != LAID_OUT:
            self.refused += 1
            return
        self._reveal(by="page")

    def _reveal(self, by: str = "timer") -> None:
        """Show the element (once) and take the probe and its input out of the panel."""
        with self._reveal_lock:
            if self._shown:
                return
            self._shown = True
            self.shown_by = by
        if self._timer is not None:
            self._timer.cancel()
        import warnings

        with warnings.catch_warnings():  # the tab may be gone (viser warns of a closed connection)
            warnings.simplefilter("ignore")
            try:
                self.handle.visible = True
                self._probe.remove()
                self._signal.remove()
            except Exception:  # noqa: BLE001 - the tab is gone
                pass

    @property
    def shown(self) -> bool:
        """Whether the element is shown (its page said its panel is laid out, or the fallback ran)."""
        return self._shown

    def due(self) -> bool:
        """Whether the rate allows a new picture now: if not, the source need not be read
        (a virtual camera's picture is the costliest thing a frame computes). Never while the
        element is hidden (before :data:`IMAGE_SETTLE` is past)."""
        now = self.clock()
        if not self._shown and now < self._show_at:
            return False
        return now - max(self._last_push, self._last_read) >= 1.0 / self.max_rate

    def update(self, src: Any, pts: Any) -> bool:
        """Send the image if it changed (at most ``max_rate`` a second); True if sent."""
        now = self.clock()
        if not self._shown:
            if now < self._show_at:
                return False
            self._reveal()
        if src is None:
            return False
        if now - self._last_push < 1.0 / self.max_rate:
            return False
        self._last_read = now
        a = np.asarray(src)
        p = None if pts is None else np.asarray(pts, dtype=float)
        same_src = self._last_src is not None and self._last_src.shape == a.shape and np.array_equal(self._last_src, a)
        same_pts = (p is None and self._last_pts is None) or (
            p is not None and self._last_pts is not None and p.shape == self._last_pts.shape and np.array_equal(p, self._last_pts)
        )
        if same_src and same_pts:
            return False
        out = prepare_image(a, p)
        if out is None:
            return False
        self.handle.image = out
        self._last_src = a.copy()
        self._last_pts = None if p is None else p.copy()
        self._last_push = now
        self.pushes += 1
        return True

    def clear(self) -> None:
        """Forget what was sent, so the next frame sends the image again."""
        self._last_src = None
        self._last_pts = None
        self._last_push = 0.0
        self._last_read = -math.inf
