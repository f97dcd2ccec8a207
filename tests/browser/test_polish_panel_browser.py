"""UI polish a new user noticed, in a real browser (Debian's Chromium).

Each test opens a lab as a student would and checks what they see: number boxes that
show their whole value, a lab without a 3D scene that gives the window to its panel, ...
Screenshots go to ``test-artifacts/polish_*.png``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from ejsgen.cli import build
from testkit.browser import ARTIFACTS, serving


def open_lab(page, url: str) -> None:
    page.goto(url)
    page.get_by_role("button", name="Reset").first.wait_for(timeout=45_000)
    # hide the GPU-less browser's notice, which covers the top left corner
    page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")


def shot(page, name: str) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / f"polish_{name}.png"))


NUMBERS = """\
ejs: 1
title: Number boxes
model:
  variables:
    t: 0.0
    dt: 0.1
    a: {expr: "np.pi / 2"}
    b: {expr: "-np.pi / 4"}
    c: {expr: "np.pi * 100"}
    k: 250.0
  evolution:
    - code: t = t + dt
view:
  - slider: {bind: a, min: -3.14, max: 3.14, step: 0.01, label: "a set point (rad)"}
  - slider: {bind: b, min: -2.6, max: 2.6, step: 0.01, label: "b set point (rad)"}
  - slider: {bind: k, min: 1, max: 1000, step: 1, label: "Current limit (A)"}
  - number: {bind: c, step: 0.01, label: "c"}
"""


@pytest.mark.browser
def test_number_boxes_show_their_whole_value(tmp_path: Path, page):
    """A slider's box and a number field show the value to their step, never cut off."""
    spec = tmp_path / "numbers.ejs.yaml"
    spec.write_text(NUMBERS)
    with serving(build(spec, tmp_path / "out")) as (app, url):
        open_lab(page, url)
        boxes = page.locator("input.mantine-NumberInput-input")
        boxes.nth(3).wait_for()
        assert boxes.count() == 4
        shown = [boxes.nth(i).input_value() for i in range(4)]
        # to the step's precision, as the slider's own marks are
        assert shown == ["1.57", "-0.79", "250", "314.16"], shown
        panel_right = page.get_by_role("button", name="Reset").first.bounding_box()
        for i in range(4):
            box = boxes.nth(i)
            # the text fits in its box (nothing scrolled out of sight) ...
            assert box.evaluate("e => e.scrollWidth <= e.clientWidth"), (shown[i], box.evaluate("e => [e.scrollWidth, e.clientWidth]"))
            # ... and the box is inside the panel
            bb = box.bounding_box()
            assert bb["x"] + bb["width"] <= panel_right["x"] + panel_right["width"] + 1, (bb, panel_right)
        shot(page, "numbers")
