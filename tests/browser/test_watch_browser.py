"""``ejsgen run --watch`` in a real Chromium: a save shows in the open tab within a second or
two (new label, new slider range) while the simulation plays on with the values the author
did not change; a broken save shows the build error (FILE:LINE:COL, the line, the hint) as
text instead of the lab; the next good save brings the lab back."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from testkit.browser import ARTIFACTS, wait_until

pytestmark = pytest.mark.browser

SPEC = """\
ejs: 1
title: Live spring
model:
  variables:
    t: 0.0
    dt: 0.01
    x: {{value: 1.0, unit: m}}
    v: 0.0
    k: {{value: 4.0, unit: N/m}}
    p: {{value: 0.0, doc: grows at 1 per second while playing}}
    s: {s}
  evolution:
    - ode:
        equations:
          x: v
          v: -k*x
          p: 1.0
view:
  - slider: {{bind: k, min: 1, max: {kmax}, step: 1, label: Stiffness}}
  - label: {{text: "{word}: p={{p:.2f}} s={{s:.2f}} k={{k:.0f}}"}}
  - scene:
      - sphere: {{position: [x, 0, 0], radius: 0.1, color: {color}}}
simulation:
  fps: 30
"""

LABEL = re.compile(r"(\w+): p=([0-9.]+) s=([0-9.]+) k=([0-9]+)")


class Watching:
    """``ejsgen run --watch SPEC --port 0`` in its own process, as an author starts it."""

    def __init__(self, spec: Path, tmp: Path) -> None:
        self.out, self.err = tmp / "out.txt", tmp / "err.txt"
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        self.proc = subprocess.Popen([sys.executable, "-P", "-m", "ejsgen", "run", "--watch", str(spec), "--port", "0"],
                                     stdout=self.out.open("w"), stderr=self.err.open("w"), env=env, cwd=tmp)
        deadline = time.monotonic() + 120
        while (m := re.search(r"serving on http://127\.0\.0\.1:(\d+)", self.out.read_text())) is None:
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"ejsgen run --watch did not serve:\n{self.out.read_text()}\n{self.err.read_text()}")
            time.sleep(0.1)
        self.url = f"http://127.0.0.1:{m.group(1)}"

    def rebuilt_lines(self) -> list[str]:
        return [line for line in self.out.read_text().splitlines() if ": rebuilt in " in line]

    def stop(self) -> int:
        self.proc.terminate()
        try:
            return self.proc.wait(20)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            raise


def shown(page) -> tuple[str, float, float, int] | None:
    """The lab's label as the user reads it: (word, p, s, k), or None while it is not there."""
    for text in page.get_by_text(LABEL).all_inner_texts():
        m = LABEL.search(text)
        if m:
            return m.group(1), float(m.group(2)), float(m.group(3)), int(m.group(4))
    return None


def test_a_save_reloads_the_tab_keeping_its_values_and_a_broken_save_shows_the_error(page, tmp_path: Path) -> None:
    spec = tmp_path / "live.ejs.yaml"
    spec.write_text(SPEC.format(s=0.5, kmax=20, word="Before", color="steelblue"))
    lab = Watching(spec, tmp_path)
    try:
        page.goto(lab.url)
        page.get_by_role("button", name="Play").wait_for(timeout=45_000)
        slider = page.get_by_role("slider").first
        slider.focus()
        slider.press("End")  # the user sets k = 20
        wait_until(lambda: (shown(page) or ("", 0, 0, 0))[3] == 20, what="k = 20 in the label")
        page.get_by_role("button", name="Play").click()
        wait_until(lambda: (shown(page) or ("", 0, 0, 0))[1] > 1.0, what="p to grow while playing")
        address = page.url
        assert "/s/" in address

        # the author changes a label, a slider's range, an initial value and a colour
        p_before = shown(page)[1]
        spec.write_text(SPEC.format(s=2.5, kmax=50, word="After", color="crimson"))
        saved = time.monotonic()
        wait_until(lambda: (shown(page) or ("",))[0] == "After", what="the new label")
        seen = time.monotonic() - saved
        word, p, s, k = shown(page)
        assert s == 2.5  # its initial value changed: the new one
        assert k == 20  # the user's setting, not the spec's 4: the declaration of k did not change
        assert p >= p_before  # kept, not back to 0 ...
        wait_until(lambda: shown(page)[1] > p + 0.5, what="p to grow on: still playing")  # ... and playing on
        assert page.get_by_role("button", name="Pause").count() == 1
        slider = page.get_by_role("slider").first
        assert slider.get_attribute("aria-valuemax") == "50" and slider.get_attribute("aria-valuenow") == "20"
        assert page.url == address  # the same session address
        line = lab.rebuilt_lines()[-1]
        m = re.search(r"rebuilt in ([0-9.]+) s .*; ([0-9.]+) s after the save\)", line)
        assert m is not None, line
        assert float(m.group(1)) < 1.0, line  # the rebuild, spec to new model running
        assert seen < 5.0, f"the tab showed the change {seen:.2f} s after the save"
        print(f"\nwatch: {line}\nwatch: the tab showed the new label {seen:.3f} s after the save")

        # a broken save: the error, as text, instead of the lab
        spec.write_text(SPEC.format(s=2.5, kmax=50, word="After", color="crimson")
                        .replace("v: -k*x", "v: -k*xx  # <img src=x onerror=window.__pwned=1>"))
        error = page.locator("pre.ejs-build-error")
        error.wait_for()
        text = error.inner_text()
        assert re.search(rf"{re.escape(str(spec))}:16:17: error: unknown name 'xx'; did you mean 'x'\?", text), text
        assert "v: -k*xx  # <img src=x onerror=window.__pwned=1>" in text  # the offending line, shown as text
        assert "^" in text
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "watch_build_error.png"))
        assert page.locator("img[src='x']").count() == 0 and page.evaluate("window.__pwned") is None
        assert page.get_by_role("button", name="Play").count() == 0 and page.get_by_role("button", name="Pause").count() == 0
        assert "unknown name 'xx'" in lab.err.read_text()  # the terminal says it too

        # fixed: the lab comes back, with its values
        spec.write_text(SPEC.format(s=2.5, kmax=50, word="Fixed", color="crimson"))
        wait_until(lambda: (shown(page) or ("",))[0] == "Fixed", what="the lab back after the fix")
        assert page.locator("pre.ejs-build-error").count() == 0
        word, p_fixed, s, k = shown(page)
        assert k == 20 and s == 2.5 and p_fixed >= p
        assert page.url == address
    finally:
        status = lab.stop()
    assert status == 128 + 15, lab.err.read_text()
