"""Text typed by one user and shown in a label is text for every user, never HTML (issue #10, item 1).

Two browsers are open on one app. Page A types HTML into a text field whose value a
``label`` interpolates; page B must show the characters as typed, and nothing they
spell may run or take effect there: no element injected, no script run, no style applied.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from testkit.charts import plots
from testkit.browser import ARTIFACTS, serving, wait_until
from ejsgen.cli import build

SPEC = """\
ejs: 1
title: Guest book
model:
  variables:
    t: 0.0
    dt: 0.1
    who: nobody
  evolution:
    - code: t = t + dt
view:
  - text: {bind: who, label: Name}
  - label: {text: "**Last visitor:** {who}"}
  - folder:
      label: "Folder of {who}"
      children:
        - slider: {bind: t, min: 0, max: 1000, label: "slider of {who}"}
        - button: {label: "button of {who}", action: "who = 'nobody'"}
  - tabs:
      tabs:
        "tab of {who}":
          - image: {source: "np.zeros((4, 4), dtype=np.uint8)", label: "image of {who}"}
  - plot: {title: "plot of {who}", series: [{y: t, label: "series of {who}"}]}
"""

PAYLOADS = [
    '<img src=x onerror="window.__pwned=1">',
    "<style>body{display:none}</style>",
    '<iframe srcdoc="<script>parent.__pwned=2</script>"></iframe>',
    "![x](/etc/hostname)  **not bold**    <b>not bold</b>",
    '<svg onload="window.__pwned=3"></svg>',
]


@pytest.fixture
def guest_book(tmp_path: Path):
    spec = tmp_path / "guest.ejs.yaml"
    spec.write_text(SPEC)
    with serving(build(spec, tmp_path / "out")) as (app, url):
        yield app, url


def open_page(context, url: str):
    page = context.new_page()
    page.goto(url)
    page.wait_for_selector("canvas", state="attached", timeout=45_000)
    page.get_by_text("Last visitor:").first.wait_for(timeout=45_000)
    return page


@pytest.mark.browser
def test_typed_html_is_shown_as_text_in_another_browser(guest_book, browser_context):
    app, url = guest_book
    page_a = open_page(browser_context, url)
    page_b = open_page(browser_context, url)
    try:
        # the author's own Markdown is Markdown
        assert page_b.locator("strong", has_text="Last visitor:").count() == 1
        field = page_a.get_by_role("textbox").first
        for payload in PAYLOADS:
            field.fill(payload)
            field.press("Enter")
            wait_until(lambda: app.model.who == payload, what=f"the model to hold {payload!r}")
            # page B shows the characters themselves (spaces kept) ...
            shown = page_b.locator("p", has_text="Last visitor:").first
            wait_until(lambda: shown.inner_text().replace("\xa0", " ") == f"Last visitor: {payload}", timeout=20,
                       what=f"page B to show {payload!r} as text")
            # ... and nothing they spell took effect there
            assert page_b.locator("iframe").count() == 0
            assert page_b.locator("img[src='x']").count() == 0
            assert page_b.locator("style", has_text="display:none").count() == 0
            assert shown.locator("b, strong:not(:first-child), img").count() == 0
            assert page_b.evaluate("window.__pwned") is None
            assert page_b.evaluate("getComputedStyle(document.body).display") != "none"
            assert page_b.get_by_role("button", name="Reset", exact=True).is_visible()
            # every other label that shows the value shows it as text too
            for kind in ("Folder", "slider", "button", "tab", "image", "series"):
                wait_until(lambda: page_b.get_by_text(f"{kind} of {payload}", exact=False).count() > 0, timeout=20,
                           what=f"the {kind}'s label to show {payload!r} as text")
            # the plot's title is drawn on its canvas (fillText: text, never markup)
            wait_until(lambda: any(p["title"] == f"plot of {payload}" and p["drawn"] for p in plots(page_b)), timeout=20,
                       what=f"the plot's title to be drawn as {payload!r}")
        ARTIFACTS.mkdir(exist_ok=True)
        page_b.screenshot(path=str(ARTIFACTS / "ui_polish_injection_page_b.png"))
    finally:
        page_a.close()
        page_b.close()
