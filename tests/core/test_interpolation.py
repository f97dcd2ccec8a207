"""{expr} and {expr:fmt} in every text property of the view (item 8 of issue #10).

Labels of sliders, numbers, checkboxes, text fields, dropdowns, buttons, folders, tabs,
plot titles, series labels and image labels are literal text in which ``{expr}`` is
interpolated, as in an f-string: a spec using them is built, served, and the handles in
the panel show the values -- and follow them when the model changes.
"""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np
import pytest

from ejsgen.cli import build
from ejsrl.view.elements import escape_markdown, escaped, format_value, keep_spaces

SPEC = """\
ejs: 1
title: Labels
model:
  variables:
    t: {value: 0.0, unit: s}
    dt: 0.1
    L: {value: 1.5, unit: m}
    theta: {value: 0.25, unit: rad}
    omega: {value: 0.5, unit: rad}
    on: true
    who: ada
    mode: slow
    n: 3
    img: {expr: "np.zeros((8, 8, 3), dtype=np.uint8)"}
  evolution:
    - code: t = t + dt
view:
  - folder:
      label: "Arm of {L:.2f} m"
      children:
        - slider: {bind: L, min: 0.5, max: 3, label: "Length {L:.1f} m"}
        - number: {bind: n, label: "n = {n}"}
        - checkbox: {bind: on, label: "on is {on}"}
        - text: {bind: who, label: "name ({len(who)} letters)"}
        - dropdown: {bind: mode, options: [slow, fast], label: "mode: {mode!r}"}
        - button: {label: "Double L (now {L:.1f})", action: "L = 2*L"}
  - tabs:
      tabs:
        "Run {n}":
          - label: {text: "inside"}
  - plot:
      title: "Angle at L = {L:.2f}"
      series: [{y: theta, label: "θ ({L:.1f})"}, {y: omega}]
  - image: {source: img, label: "camera {n}x"}
"""


@pytest.fixture
def served(tmp_path: Path):
    from ejsrl.app import load_app
    from ejsrl.view.viser_view import ViserView, make_server

    spec = tmp_path / "labels.ejs.yaml"
    spec.write_text(SPEC)
    app = load_app(build(spec, tmp_path / "out"))
    server, _url = make_server("127.0.0.1", 0)
    view = ViserView(app, server)
    try:
        yield app, view
    finally:
        server.stop()


def test_every_label_kind_shows_and_follows_its_values(served) -> None:
    app, view = served
    panel = view.panel
    labels = {key: h.label for key, h in panel.handles_by_label.items()}
    assert labels == {
        "Length {L:.1f} m": "Length 1.5 m",
        "n = {n}": "n = 3",
        "on is {on}": "on is True",
        "name ({len(who)} letters)": "name (3 letters)",
        "mode: {mode!r}": "mode: 'slow'",
    }
    assert panel.buttons["Double L (now {L:.1f})"].label == "Double L (now 1.5)"
    plot = panel.plots[0]
    assert plot.handle.last_frame["title"] == "Angle at L = 1.50"
    assert [e["label"] for e in plot.handle.last_frame["legend"]] == ["θ (1.5)", "omega"]
    assert panel.images[0].handle.label == "camera 3x"
    folder = [h for h in panel.gui._container_handle_from_uuid.values() if getattr(h, "label", None) == "Arm of 1.50 m"]
    assert len(folder) == 1
    tab_groups = {id(h._parent): h._parent for h in panel.gui._container_handle_from_uuid.values() if hasattr(h, "_parent")}.values()
    assert any(tuple(g._tab_labels) == ("Run 3",) for g in tab_groups)

    # the model changes (a button press): every label follows on the next frame
    with app.lock:
        app.run_action(panel.app.view[0].children[5])
        app.model.n = 12
        view.on_frame()
    assert app.model.L == 3.0
    assert panel.handles_by_label["Length {L:.1f} m"].label == "Length 3.0 m"
    assert panel.handles_by_label["n = {n}"].label == "n = 12"
    assert panel.buttons["Double L (now {L:.1f})"].label == "Double L (now 3.0)"
    assert plot.handle.last_frame["title"] == "Angle at L = 3.00"
    assert [e["label"] for e in plot.handle.last_frame["legend"]] == ["θ (3.0)", "omega"]
    assert panel.images[0].handle.label == "camera 12x"
    assert folder[0].label == "Arm of 3.00 m"
    assert any(tuple(g._tab_labels) == ("Run 12",) for g in tab_groups)


def test_plot_axes_are_titled_with_units(served) -> None:
    _app, view = served
    axes = view.panel.plots[0].handle.last_frame["axes"]
    assert axes["x"]["title"] == "t (s)"  # x's unit
    assert axes["y"]["title"] == "rad"  # both series are in rad


@pytest.mark.parametrize(
    "payload",
    [
        '<img src=x onerror="window.__pwned=1">',
        "<style>body{display:none}</style>",
        '<iframe srcdoc="<script>parent.__pwned=1</script>">',
        "![secret](/etc/hostname) [link](javascript:alert(1)) **bold** `code` # head",
        "    indented code\n- item\n1. item",
        "&lt;b&gt; &amp;",
    ],
)
def test_escaped_values_render_as_their_own_text(payload: str) -> None:
    """A CommonMark renderer with raw HTML on (as viser's) shows the value's characters, no markup."""
    from markdown_it import MarkdownIt

    md = MarkdownIt("commonmark")  # html: True, like viser's renderer
    out = md.render("value: " + keep_spaces(escaped(payload)))
    body = out.removeprefix("<p>").removesuffix("</p>\n")
    if "\n" in payload:  # several lines: one monospace block
        assert body.startswith('value: <span style="display:inline-block') and body.endswith("</span>")
        body = "value: " + body.split(">", 1)[1].removesuffix("</span>")
    assert "<" not in body.replace("<br>", "").replace("<br />", "")  # no element but line breaks
    shown = html.unescape(body.replace("<br />", "\n").replace("<br>", "\n")).replace("\xa0", " ")
    assert shown == "value: " + payload


def test_escape_keeps_letters_and_is_undone_by_html_unescape() -> None:
    text = "θ = 0.5 naïve (a_b) <x> & 'q'"
    out = escape_markdown(text)
    assert html.unescape(out) == text
    assert "θ" in out and "naïve" in out
    assert not set("<>&()_'") & set(out.replace("&#", "").replace(";", ""))


def test_keep_spaces_keeps_runs_and_indents() -> None:
    assert keep_spaces("a  b") == "a &nbsp;b"
    assert keep_spaces("    x") == "&nbsp;&nbsp;&nbsp;&nbsp;x"
    assert keep_spaces("a\nb") == "a<br>b"


def test_matrix_values_are_formatted_as_aligned_rows() -> None:
    T = np.array([[1.0, 0.0, 0.0, 0.25], [0.0, -1.0, 0.0, -12.5], [0.0, 0.0, 1.0, 0.5], [0.0, 0.0, 0.0, 1.0]])
    rows = format_value(T, "+.3f").splitlines()
    assert rows[0] == "[ +1.000  +0.000  +0.000  +0.250]"
    assert rows[1] == "[ +0.000  -1.000  +0.000 -12.500]"
    assert len({len(r) for r in rows}) == 1  # aligned
    assert format_value(np.array([1, 2, 3]), "") == "[1 2 3]"
    assert format_value(2.5, ".2f") == "2.50"
    assert format_value("ab", ">4") == "  ab"
    shown = escaped(T, "+.3f")
    assert shown.count("<br>") == 3 and "monospace" in shown


@pytest.mark.parametrize(
    "text",
    ["Energy: {E:.3f} J", "{a!r:>8}|{b}", "{{x}} {y} }}", "t = {t:.2f} s   E = {E:.4f} J", "{q[2]:+.3f}", "plain"],
)
def test_fields_split_as_python_s_formatter_splits_them(text: str) -> None:
    """Where the formatter can read a text, the scanner reads it the same way."""
    import string

    from ejsgen._interpolate import Field, split_fields

    ours = [(p.expr, p.spec, p.conversion) for p in split_fields(text) if isinstance(p, Field)]
    theirs = [(f, s, c) for _, f, s, c in string.Formatter().parse(text) if f is not None]
    assert ours == theirs
    literal = "".join(p for p in split_fields(text) if isinstance(p, str))
    assert literal == "".join(lit for lit, *_ in string.Formatter().parse(text))


@pytest.mark.parametrize(
    ("text", "offset", "says"),
    [
        ("s = {np.array([a, b):.2f}", 14, "'[' is closed by ')'"),
        ("s = {f(a:.2f}", 6, "'(' is never closed"),
        ("n = {'abc}", 5, "quote ' is never closed"),
        ("x = {a:.2f", 4, "'{' is never closed"),
        ("x = a}", 5, "'}' closes no '{'"),
        ("x = {a!z}", 6, "'!z' is not a conversion"),
    ],
)
def test_a_malformed_text_is_reported_at_the_character_to_fix(text: str, offset: int, says: str) -> None:
    from ejsgen._interpolate import BraceError, split_fields

    with pytest.raises(BraceError) as err:
        split_fields(text)
    assert err.value.offset == offset and says in err.value.message


def test_expressions_with_brackets_strings_and_not_equal_interpolate(tmp_path) -> None:
    """'!=' and a '}' inside a string or brackets belong to the expression, as in an f-string."""
    from ejsgen.cli import build
    from ejsrl.app import load_app

    spec = tmp_path / "s.ejs.yaml"
    spec.write_text(
        "ejs: 1\ntitle: S\nmodel:\n  variables:\n    a: 2\n    q: [1.5, 2.5]\n"
        "view:\n  - label: {text: \"{a != 0} {'}'} {[a, 7][1]} {q[1]:+.1f} {{a}}\"}\n"
    )
    app = load_app(build(spec, tmp_path / "out"))
    label = app.view[0].text
    assert html.unescape(label(app.model)) == "True } 7 +2.5 {a}"
