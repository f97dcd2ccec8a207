"""Reading uPlot charts in the browser as a user sees them: the text each chart draws (its axis
labels), recorded by an init script, and split into x and y tick labels."""

from __future__ import annotations

import math
from collections import Counter

from ejsrl.sim.model import CodePage, ModelBase

#: add with ``page.add_init_script``: records, per canvas, the text drawn since its last clear
RECORD_TEXT = """
window.__texts = new Map();
const C = CanvasRenderingContext2D.prototype;
const fill = C.fillText, clear = C.clearRect;
C.clearRect = function (...a) { window.__texts.set(this.canvas, []); return clear.apply(this, a); };
C.fillText = function (t, x, y, ...r) {
  const l = window.__texts.get(this.canvas) || [];
  l.push([String(t), x, y]);
  window.__texts.set(this.canvas, l);
  return fill.call(this, t, x, y, ...r);
};
"""


def tick_labels(texts: list) -> tuple[list[str], list[str]]:
    """(x tick labels, y tick labels) of a chart's recorded ``[text, x, y]``: the x ticks share a
    baseline, the y ticks a left edge."""
    by_y = Counter(round(t[2], 1) for t in texts)
    by_x = Counter(round(t[1], 1) for t in texts)
    row = by_y.most_common(1)[0][0] if by_y else None
    col = by_x.most_common(1)[0][0] if by_x else None
    xs = [t[0] for t in texts if round(t[2], 1) == row]
    ys = [t[0] for t in texts if round(t[1], 1) == col and round(t[2], 1) != row]
    return xs, ys


def tick_number(label: str) -> float:
    """A tick label's value ("1,000" and a minus sign as uPlot writes them)."""
    return float(label.replace(",", "").replace("\u2212", "-"))


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
