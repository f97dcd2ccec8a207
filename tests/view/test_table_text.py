"""The ``table`` and ``console`` elements and Markdown tables in labels, at the server.

A lab is built from a spec, served, and its panel's HTML read back cell by cell with an
HTML parser: the values, their variables' units, the format, an array's headers and
units, rows left out, markup typed into a string variable shown as text. The console shows
what its own simulation printed (another simulation's prints never), bounded, escaped, and
its Clear button empties it. A label's Markdown table is parsed by an independent GFM
renderer (markdown-it-py) into a table whose cells hold the escaped values. The browser
test (tests/browser/test_text_elements_browser.py) checks the same on screen.
"""

from __future__ import annotations

import html
from html.parser import HTMLParser
from pathlib import Path

import pytest

from ejsgen.cli import build
from ejsrl.app import load_app

SPEC = """\
ejs: 1
title: Text lab
model:
  variables:
    t: 0.0
    dt: 0.1
    k: {value: 2.5, unit: N/m}
    x: {value: 0.5, unit: m}
    name: "<img src=x onerror=alert(1)>"
    data: [[0, 1.5], [1, 2.25], [2, 3.125]]
    many: {expr: "np.arange(250.0)"}
  init: |
    print("init: k =", k)
  evolution:
    - code: |
        t = t + dt
  custom: |
    def hello(who):
        print(f"hello {who}")
    def shout(n):
        for i in range(n):
            print("line", i)
view:
  - table: {title: Values, rows: [k, x, name, {value: "k*x", label: force, unit: N, format: ".3e"}]}
  - table: {data: data, columns: [t, y], units: [s, m], format: ".2f"}
  - table: {data: many, columns: [n], max_rows: 100, format: d}
  - console: {lines: 50}
  - button: {label: Hi, action: "hello(name)"}
  - button: {label: Shout, action: "shout(300)"}
  - label:
      text: |
        Results
        | name | value |
        |---|--:|
        | k | {k:.2f} |
        | who | {name} |
"""


class _Cells(HTMLParser):
    """The text of every <th>/<td> of an HTML fragment, row by row (entities decoded)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.rows: list[list[str]] = []
        self.tags: list[str] = []
        self._cell: list[str] | None = None

    def handle_starttag(self, tag: str, attrs: list) -> None:
        self.tags.append(tag)
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self._cell = []
        elif tag == "br" and self._cell is not None:
            self._cell.append(" ")

    def handle_endtag(self, tag: str) -> None:
        if tag in ("td", "th") and self._cell is not None:
            self.rows[-1].append("".join(self._cell).strip())
            self._cell = None

    def handle_data(self, data: str) -> None:
        if self._cell is not None:
            self._cell.append(data)


def cells(fragment: str) -> _Cells:
    p = _Cells()
    p.feed(fragment)
    return p


@pytest.fixture(scope="module")
def app_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("text")
    (root / "lab.ejs.yaml").write_text(SPEC)
    return build(root / "lab.ejs.yaml", root / "app")


@pytest.fixture
def served(app_dir: Path):
    from ejsrl.view.viser_view import ViserView, make_server

    app = load_app(app_dir)
    server, _url = make_server("127.0.0.1", 0, banner=False)
    view = ViserView(app, server)
    app.views.append(view)
    yield app, view
    server.stop()


def _bindings(view):
    from ejsrl.view._console import ConsoleBinding
    from ejsrl.view._table import TableBinding

    tables = [b for b in view.panel.text_views if isinstance(b, TableBinding)]
    consoles = [b for b in view.panel.text_views if isinstance(b, ConsoleBinding)]
    return tables, consoles


def test_rows_show_each_value_with_its_variables_unit_and_follow_the_model(served) -> None:
    app, view = served
    (values, _data, _many), _ = _bindings(view)
    got = cells(values.handle.content)
    assert got.rows[1:] == [
        ["k", "2.5", "N/m"],
        ["x", "0.5", "m"],
        ["name", "<img src=x onerror=alert(1)>", ""],  # the text itself, once the page decodes it
        ["force", format(2.5 * 0.5, ".3e"), "N"],
    ]
    assert "<img" not in values.handle.content and "&lt;img src=x onerror=alert(1)&gt;" in values.handle.content
    assert "img" not in cells(values.handle.content).tags
    with app.lock:
        app.model.k = 4.0
        app.model.name = "</td></tr></table><b>x</b>"
    app.frame()
    got = cells(values.handle.content)
    assert got.rows[1] == ["k", "4", "N/m"] and got.rows[4] == ["force", format(4.0 * 0.5, ".3e"), "N"]
    assert got.rows[3] == ["name", "</td></tr></table><b>x</b>", ""] and len(got.rows) == 5
    assert "b" not in got.tags


def test_an_array_is_a_table_with_headers_units_and_the_format(served) -> None:
    _app, view = served
    (_values, data, many), _ = _bindings(view)
    got = cells(data.handle.content)
    assert got.rows == [["t s", "y m"], ["0.00", "1.50"], ["1.00", "2.25"], ["2.00", "3.12"]]
    long = cells(many.handle.content)
    assert long.rows[0] == ["n"]
    assert [r[0] for r in long.rows[1:101]] == [str(i) for i in range(100)]  # 'd' on whole floats: 0, 1, ...
    assert long.rows[101] == ["… 150 more rows"] and len(long.rows) == 102


def test_the_console_shows_its_own_simulations_prints_escaped_bounded_and_clears(app_dir: Path) -> None:
    from ejsrl.view.viser_view import ViserView, make_server

    apps, views, servers = [], [], []
    for _ in range(2):  # two simulations: two browser tabs of a classroom
        app = load_app(app_dir)
        server, _url = make_server("127.0.0.1", 0, banner=False)
        view = ViserView(app, server)
        app.views.append(view)
        apps.append(app)
        views.append(view)
        servers.append(server)
    try:
        (_, [one]), (_, [two]) = _bindings(views[0]), _bindings(views[1])
        text = lambda c: html.unescape(c.handle.content)  # noqa: E731 - what the page shows
        assert "init: k = 2.5" in text(one) and "init: k = 2.5" in text(two)
        hi = next(b for b in apps[0].view if getattr(b, "label", None) == "Hi")
        apps[0].run_action(hi)
        apps[0].frame()
        apps[1].frame()
        assert "hello <img src=x onerror=alert(1)>" in text(one)
        assert "<img" not in one.handle.content  # escaped: shown, never run
        assert "hello" not in text(two)  # the other tab's simulation printed nothing of the kind
        shout = next(b for b in apps[0].view if getattr(b, "label", None) == "Shout")
        apps[0].run_action(shout)
        apps[0].frame()
        box = html.unescape(one.handle.content.split("<div>", 1)[1].rsplit("</div></div>", 1)[0]).split("\n")
        assert box == [f"line {i}" for i in range(250, 300)]  # the last 50 (lines: 50)
        one.clear_button._impl.update_cb[0](None)  # the Clear button, pressed
        assert "nothing printed yet" in one.handle.content and "line 299" not in one.handle.content
        assert "init: k = 2.5" in text(two)
    finally:
        for s in servers:
            s.stop()


def test_a_headless_run_prints_to_standard_output_as_before(app_dir: Path) -> None:
    from testkit import run_app

    r = run_app(app_dir, "--headless", "--duration", "0.2")
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0] == "init: k = 2.5"


def test_the_console_log_keeps_the_last_lines_and_joins_a_line_printed_in_pieces() -> None:
    from ejsrl.sim._console import ConsoleLog

    log = ConsoleLog()
    log.write("step at 0.3")
    assert log.lines() == ["step at 0.3"]
    log.write(" done\nnext\n")
    assert log.lines() == ["step at 0.3 done", "next"]
    for i in range(ConsoleLog.MAX_LINES + 10):
        log.write(f"{i}\n")
    assert len(log.lines()) == ConsoleLog.MAX_LINES and log.lines()[-1] == str(ConsoleLog.MAX_LINES + 9)
    log.write("x" * (ConsoleLog.MAX_LINE + 500) + "\n")
    assert len(log.lines()[-1]) == ConsoleLog.MAX_LINE and log.lines()[-1].endswith("…")
    assert log.lines(3)[:2] == [str(ConsoleLog.MAX_LINES + 8), str(ConsoleLog.MAX_LINES + 9)]


def test_a_markdown_table_in_a_label_is_a_table_with_its_values_escaped(served) -> None:
    from markdown_it import MarkdownIt

    app, view = served
    with app.lock:
        app.model.name = "a | b <script>x</script>"
    app.frame()
    (_label, handle) = view.panel.labels[0]
    page = MarkdownIt("commonmark", {"html": True}).enable("table").render(handle.content)
    got = cells(page)
    assert got.rows == [["name", "value"], ["k", "2.50"], ["who", "a | b <script>x</script>"]]  # one cell: its | is text
    assert "script" not in got.tags and "<p>Results</p>" in page


def test_text_without_a_table_keeps_its_spaces_and_line_breaks() -> None:
    from ejsrl.view.elements import keep_spaces

    assert keep_spaces("a  b\n  c") == "a &nbsp;b<br>&nbsp;&nbsp;c"
    assert keep_spaces("x | y\nno rule here") == "x | y<br>no rule here"  # a pipe alone makes no table


def test_an_array_changed_in_place_is_shown_and_an_unchanged_table_is_not_rebuilt(served) -> None:
    app, view = served
    (_values, data, _many), _ = _bindings(view)
    before = data.shown
    app.frame()
    assert data.shown is before  # nothing changed: not formatted again, nothing sent
    with app.lock:
        app.model.data[1, 1] = 9.0  # the same array object, one element changed
    app.frame()
    assert cells(data.handle.content).rows[2] == ["1.00", "9.00"]
