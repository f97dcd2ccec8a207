"""Reading plots in the browser as a user sees them.

Plots are drawn by the 2D panel engine (``window.__ejs2d``) on canvases inside
``div[data-ejs2d]`` whose ``data-key`` starts with ``plot-``. :data:`PLOTS` reads, per plot,
the frame the engine holds (title, bounds, axes with their ticks, items) and the text drawn
on its canvas since its last clear (recorded by :data:`RECORD_TEXT`, an init script that
wraps ``fillText``); :func:`tick_labels` splits that text into x and y tick labels;
:func:`plot_pixels` is the canvas as the user sees it, and :func:`to_px` where a data point
lands on it.
"""

from __future__ import annotations

import io
import math
from collections import Counter
from typing import Any

import numpy as np

from ejsrl.sim.model import CodePage, ModelBase

#: add with ``page.add_init_script``: records, per canvas, the text drawn since its last clear
RECORD_TEXT = """
window.__texts = new Map();
const C = CanvasRenderingContext2D.prototype;
const fill = C.fillText, clear = C.clearRect;
C.clearRect = function (...a) { window.__texts.set(this.canvas, []); return clear.apply(this, a); };
C.fillText = function (t, x, y, ...r) {
  const l = window.__texts.get(this.canvas) || [];
  const m = this.getTransform();
  l.push([String(t), m.a === 0 ? x : m.e / m.a + x, m.d === 0 ? y : m.f / m.d + y, m.b !== 0 || m.c !== 0]);
  window.__texts.set(this.canvas, l);
  return fill.call(this, t, x, y, ...r);
};
"""

#: every plot on the page: its key, panel id, frame (title, bounds, axes, items) and drawn text
PLOTS = """
() => Array.from(document.querySelectorAll('div[data-ejs2d]')).filter(d => (d.dataset.key || '').startsWith('plot-')).map(d => {
  const p = (window.__ejs2d && window.__ejs2d.panels[d.dataset.ejs2d]) || {};
  const f = p.frame || null, c = d.querySelector('canvas'), r = c.getBoundingClientRect();
  return {
    key: d.dataset.key, id: d.dataset.ejs2d, drawn: p.drawn || 0,
    title: f ? f.title : null, bounds: f ? f.bounds : null,
    x: f && f.axes ? f.axes.x : null, y: f && f.axes ? f.axes.y : null,
    legend: f ? f.legend : [], items: f ? f.items : [],
    texts: (window.__texts && window.__texts.get(c)) || [],
    width: r.width, height: r.height,
  };
})
"""


def plots(page: Any) -> list[dict]:
    """Every plot on the page (see :data:`PLOTS`)."""
    return page.evaluate(PLOTS)


def plot(page: Any, title: str) -> dict:
    """The plot titled ``title`` ({} if there is none yet)."""
    found = [p for p in plots(page) if p["title"] == title]
    return found[0] if found else {}


def frame_ticks(p: dict) -> tuple[list[str], list[str]]:
    """(x tick labels, y tick labels) the server sent the plot."""
    return [t[1] for t in (p.get("x") or {}).get("ticks", [])], [t[1] for t in (p.get("y") or {}).get("ticks", [])]


def tick_labels(texts: list) -> tuple[list[str], list[str]]:
    """(x tick labels, y tick labels) of a plot's drawn ``[text, x, y, rotated]``: the x ticks
    share a baseline (the most common one), the y ticks a right edge left of every other text
    (rotated text, the y axis' title, is left out)."""
    texts = [t for t in texts if not (len(t) > 3 and t[3])]
    by_y = Counter(round(t[2], 1) for t in texts)
    row = by_y.most_common(1)[0][0] if by_y else None
    rest = [round(t[1], 1) for t in texts if round(t[2], 1) != row]
    col = min(rest) if rest else None  # the y ticks' right edge is left of every other text
    xs = [t[0] for t in texts if round(t[2], 1) == row]
    ys = [t[0] for t in texts if round(t[1], 1) == col and round(t[2], 1) != row]
    return xs, ys


def tick_number(label: str) -> float:
    """A tick label's value (a minus sign as the plots write it, U+2212)."""
    return float(label.replace(",", "").replace("\u2212", "-"))


def plot_pixels(page: Any, p: dict) -> np.ndarray:
    """The plot's canvas as the user sees it: (H, W, 3) int, one pixel per CSS pixel."""
    from PIL import Image

    png = page.locator(f'div[data-ejs2d="{p["id"]}"] canvas').screenshot()
    img = Image.open(io.BytesIO(png)).convert("RGB")
    if img.size != (round(p["width"]), round(p["height"])):
        img = img.resize((round(p["width"]), round(p["height"])))
    return np.asarray(img).astype(int)


def to_px(page: Any, p: dict, x: float, y: float) -> tuple[float, float]:
    """Where data point (x, y) lands on the plot's canvas (CSS pixels from its top left)."""
    got = page.evaluate("([id, x, y]) => window.__ejs2d.toPx(id, x, y)", [p["id"], x, y])
    assert got is not None, "the plot has not been drawn"
    return float(got[0]), float(got[1])


def near_color(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 60) -> np.ndarray:
    """(N, 2) pixel coordinates (column, row) whose colour is within ``tol`` of ``rgb``."""
    d = np.abs(img - np.asarray(rgb)).sum(axis=2)
    rows, cols = np.nonzero(d <= tol)
    return np.column_stack((cols, rows))


class Strip(ModelBase):
    """A strip chart's lab: ``y = sin(3 t)`` and a near-constant ``E`` (a flat line), 50 steps a second."""

    SPEC = "strip.ejs.yaml"
    VARIABLES = {"t": "float", "dt": "float", "y": "float", "E": "float"}
    INDEPENDENT = "t"

    def _declare(self) -> None:
        self.t = 0.0
        self.dt = 0.02
        self.y = 0.0
        self.E = 0.196

    def _evolution(self) -> list:
        return [CodePage("step", self._step)]

    def _step(self) -> None:
        self.t += self.dt

    def _fixed_relations(self) -> None:
        self.y = math.sin(3.0 * self.t)
        self.E = 0.196 + 1e-10 * self.t
