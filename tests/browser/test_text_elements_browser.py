"""Tables, consoles and Markdown tables in a real browser, two tabs on one classroom-served lab.

What a user sees: the table of values with its units and the array table with its headers;
text typed into a field shows in the table as text (no element made of it, no script run);
each tab's console shows only what its own simulation printed, markup as text, and its
Clear button empties that tab's console only; a Markdown table in a label and in a
``markdown`` element is drawn as an HTML table.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from testkit.browser import ARTIFACTS, wait_until

SLOW = 120_000

SPEC = """\
ejs: 1
title: Text elements
model:
  variables:
    t: 0.0
    dt: 0.1
    k: {value: 2.5, unit: N/m}
    name: "<b>bold</b>"
    data: [[0, 1.5], [1, 2.25]]
  init: |
    print("ready")
  custom: |
    def hello(who):
        print(f"hello {who}")
    def count(n):
        for i in range(n):
            print("line", i)
view:
  - text: {bind: name, label: Name}
  - table: {rows: [k, name]}
  - table: {data: data, columns: [time, y], units: [s, m], format: ".2f"}
  - button: {label: Hi, action: "hello(name)"}
  - button: {label: Count, action: "count(3)"}
  - console: {lines: 20}
  - markdown:
      text: |
        | static | table |
        |---|---|
        | a | b |
  - label:
      text: |
        | quantity | value |
        |---|--:|
        | k | {k:.2f} |
        | who | {name} |
"""


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory):
    from ejsgen.cli import build
    from ejsrl.app import load_app

    root = tmp_path_factory.mktemp("text-browser")
    (root / "lab.ejs.yaml").write_text(SPEC)
    app = load_app(build(root / "lab.ejs.yaml", root / "app"))
    server = app.serve("127.0.0.1", 0, block=False, per_client=True, max_sessions=2, grace=30.0)
    yield app, f"http://127.0.0.1:{server.get_port()}"
    app.stop()
    server.stop()


def _open(context, url: str):
    page = context.new_page()
    page.bring_to_front()
    page.set_default_timeout(SLOW)
    page.goto(url)
    page.locator(".ejs-console").wait_for()
    wait_until(lambda: "/s/" in page.evaluate("location.href"), what="the tab's address to carry its session")
    return page


def _session(app, page):
    token = re.search(r"/s/([A-Za-z0-9_-]+)/", page.evaluate("location.href")).group(1)
    return app.classroom.sessions[token].app


def _console(page) -> str:
    return page.locator(".ejs-console").inner_text()


@pytest.mark.browser
def test_tables_consoles_and_markdown_tables_per_tab(lab, browser_context) -> None:
    app, url = lab
    a = _open(browser_context, url)
    b = _open(browser_context, url)
    try:
        sa, sb = _session(app, a), _session(app, b)
        assert sa is not sb

        # the table of values: each variable with its value and unit; the array with headers, units, format
        a.bring_to_front()
        values = a.locator("table.ejs-table").nth(0)
        assert values.locator("tbody tr").nth(0).locator("td").all_inner_texts() == ["k", "2.5", "N/m"]
        assert values.locator("tbody tr").nth(1).locator("td").all_inner_texts() == ["name", "<b>bold</b>", ""]
        array = a.locator("table.ejs-table").nth(1)
        assert [h.replace("\n", " ") for h in array.locator("th").all_inner_texts()] == ["time s", "y m"]
        assert [r.locator("td").all_inner_texts() for r in array.locator("tbody tr").all()] == [["0.00", "1.50"], ["1.00", "2.25"]]

        # text typed by a user shows in the table as text: no element made of it, no script run
        typed = '<img src=x onerror="window.__ejsPwned=1">'
        field = a.get_by_role("textbox").first
        field.fill(typed)
        field.press("Enter")
        wait_until(lambda: sa.model.name == typed, what="the typed name in A's simulation")
        values.locator("td", has_text="onerror").wait_for()
        assert values.locator("tbody tr").nth(1).locator("td").nth(1).inner_text() == typed
        assert a.locator("table.ejs-table img").count() == 0
        assert a.evaluate("window.__ejsPwned") is None

        # each tab's console: its own prints, markup as text
        assert "ready" in _console(a) and "ready" in _console(b)
        a.get_by_role("button", name="Hi").click()
        a.locator(".ejs-console", has_text="hello").wait_for()
        assert "hello " + typed in _console(a)
        assert a.locator(".ejs-console img").count() == 0 and a.evaluate("window.__ejsPwned") is None
        b.bring_to_front()
        b.get_by_role("button", name="Hi").click()
        b.locator(".ejs-console", has_text="hello <b>bold</b>").wait_for()
        assert b.locator(".ejs-console b").count() == 0
        b.get_by_role("button", name="Count").click()
        b.locator(".ejs-console", has_text="line 2").wait_for()
        a.bring_to_front()
        a.wait_for_timeout(500)  # frames enough for a print in B to show in A, were it shown there
        assert "line 2" not in _console(a) and "<b>bold</b>" not in _console(a)

        # Clear empties this tab's console only
        a.get_by_role("button", name="Clear console").click()
        a.locator(".ejs-console", has_text="nothing printed yet").wait_for()
        b.bring_to_front()
        assert "line 2" in _console(b)

        # Markdown tables (a markdown element, a label with values) are drawn as tables
        static = b.locator("table", has_text="static")
        assert static.locator("td").all_inner_texts() == ["a", "b"]
        label = b.locator("table", has_text="quantity")
        assert label.locator("tbody tr").nth(0).locator("td").all_inner_texts() == ["k", "2.50"]
        assert label.locator("tbody tr").nth(1).locator("td").all_inner_texts() == ["who", "<b>bold</b>"]
        assert label.locator("b").count() == 0
        a.bring_to_front()
        label_a = a.locator("table", has_text="quantity")
        label_a.locator("td", has_text="onerror").wait_for()
        assert label_a.locator("tbody tr").nth(1).locator("td").all_inner_texts() == ["who", typed]
        assert label_a.locator("img").count() == 0 and "|" not in label_a.inner_text().replace(typed, "")
        ARTIFACTS.mkdir(exist_ok=True)
        a.screenshot(path=str(ARTIFACTS / "text_elements_tab_a.png"))
        b.bring_to_front()
        b.screenshot(path=str(ARTIFACTS / "text_elements_tab_b.png"))
    finally:
        a.close()
        b.close()


@pytest.mark.browser
def test_the_data_fitting_lab_fits_its_file_and_shows_the_fit(browser_context, tmp_path: Path) -> None:
    """examples/data_fitting in the browser: its data file read by name, Fit prints the fit in the
    console and the tables and the Markdown table show the fitted values."""
    import math

    from ejsgen.cli import build
    from ejsrl.app import load_app
    from testkit import EXAMPLES

    app = load_app(build(EXAMPLES / "data_fitting.ejs.yaml", tmp_path / "app"))
    server = app.serve("127.0.0.1", 0, block=False)
    page = browser_context.new_page()
    try:
        page.set_default_timeout(SLOW)
        page.goto(f"http://127.0.0.1:{server.get_port()}")
        page.locator(".ejs-console", has_text="read 81 points from data_fitting/measured.csv").wait_for()
        page.get_by_role("button", name="Fit").click()
        page.locator(".ejs-console", has_text="fit 1: A = ").wait_for()
        wait_until(lambda: app.model.fits == 1, what="the fit")
        fit = page.locator("table.ejs-table", has_text="The fit")
        fit.locator("td", has_text=f"{app.model.A:.4g}").first.wait_for()
        assert fit.locator("tbody tr").nth(0).locator("td").all_inner_texts() == ["A", f"{app.model.A:.4g}", "m"]
        assert abs(app.model.omega - 2 * math.pi * 0.8) < 3 * app.model.domega  # the value the data were made with
        residuals = page.locator("table.ejs-table", has_text="Residuals")
        assert residuals.locator("tbody tr").count() == 13  # 12 rows and the line counting the others
        assert residuals.locator("tbody tr").last.inner_text().strip() == "… 69 more rows"
        summary = page.locator("table", has_text="what the fit says")
        summary.locator("td", has_text=f"{2 * math.pi / app.model.omega:.4f} s").wait_for()
        ARTIFACTS.mkdir(exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "data_fitting.png"))
    finally:
        page.close()
        app.stop()
        server.stop()
