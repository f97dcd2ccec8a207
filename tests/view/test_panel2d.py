"""The 2D panel's Python side: events from the browser checked strictly, frames encoded for the
client, only new frames sent, at most at the panel's rate."""

from __future__ import annotations

import base64
import json

import numpy as np
import pytest

from ejsrl.view._panel2d import (
    ALLOWED_KEYS,
    MAX_EVENTS,
    MAX_MESSAGE_CHARS,
    Panel2D,
    encode_xy,
    frame_json,
    parse_events,
)
from testkit.clock import FakeClock


def msg(*events, s: int = 1) -> str:
    return json.dumps({"s": s, "e": list(events)})


DRAG = {"k": "drag", "id": "ball", "phase": "move", "x": 1.5, "y": -2.0}


def test_valid_events_come_back_rebuilt() -> None:
    got = parse_events(msg(DRAG, {"k": "key", "key": "ArrowUp", "phase": "down"}, {"k": "click", "x": 0, "y": 3},
                           dict(DRAG, phase="release", i=4)))
    assert got == (1, [DRAG, {"k": "key", "key": "ArrowUp", "phase": "down"}, {"k": "click", "x": 0.0, "y": 3.0},
                       dict(DRAG, phase="release", i=4)])
    assert isinstance(got[1][2]["x"], float)


@pytest.mark.parametrize("raw", [
    None, 5, b"{}", "", "not json", "[1, 2]", '{"s": 1}', '{"s": 1, "e": [], "x": 0}', '{"s": -1, "e": []}',
    '{"s": true, "e": []}', '{"s": 1.5, "e": []}', '{"s": 1, "e": {}}',
    '{"s": 1, "e": [{"k": "drag", "id": "a", "phase": "move", "x": NaN, "y": 0}]}',  # NaN is no JSON
    '{"s": 1, "e": [{"k": "click", "x": Infinity, "y": 0}]}',
    '[' * 5000,  # deep nesting
])
def test_malformed_messages_are_dropped_whole(raw) -> None:
    assert parse_events(raw) is None


def test_oversized_messages_and_too_many_events_are_dropped() -> None:
    big = msg(dict(DRAG, id="a" * 10), *[DRAG] * 3)
    assert parse_events(big + " " * (MAX_MESSAGE_CHARS - len(big) + 1)) is None
    assert parse_events(msg(*[{"k": "key", "key": "a", "phase": "down"}] * (MAX_EVENTS + 1))) is None
    assert len(parse_events(msg(*[{"k": "key", "key": "a", "phase": "down"}] * MAX_EVENTS))[1]) == MAX_EVENTS


@pytest.mark.parametrize("event", [
    dict(DRAG, x=1e10),  # beyond any world
    dict(DRAG, x=True),  # a boolean is no number
    dict(DRAG, x="1"),
    dict(DRAG, phase="fling"),
    dict(DRAG, id="<img src=x>"),
    dict(DRAG, id=""),
    dict(DRAG, id="a" * 65),
    dict(DRAG, extra=1),  # an unknown field
    {k: v for k, v in DRAG.items() if k != "y"},
    dict(DRAG, i=-1),
    dict(DRAG, i=1.0),
    {"k": "key", "key": "F5", "phase": "down"},  # not on the allow-list
    {"k": "key", "key": "Tab", "phase": "down"},
    {"k": "key", "key": "a", "phase": "press"},
    {"k": "key", "key": "a", "phase": "down", "code": "KeyA"},
    {"k": "click", "x": 0, "y": 0, "button": 2},
    {"k": "eval", "code": "alert(1)"},
    {"k": "drag"},
    "drag",
])
def test_bad_events_are_left_out_and_the_good_ones_kept(event) -> None:
    assert parse_events(msg(event, DRAG)) == (1, [DRAG])


def test_the_allowed_keys() -> None:
    assert {"a", "Z", "0", "9", "ArrowUp", "ArrowLeft", " ", "Enter", "Escape", "+", "-"} <= ALLOWED_KEYS
    assert not {"Tab", "F1", "Control", "Meta", "Backspace", "ab", ""} & ALLOWED_KEYS


def test_encode_xy_is_little_endian_float32_row_major() -> None:
    a = np.array([[1.0, 2.0], [3.5, np.nan]])
    raw = base64.b64decode(encode_xy(a))
    assert np.array_equal(np.frombuffer(raw, dtype="<f4"), np.array([1.0, 2.0, 3.5, np.nan], dtype="<f4"), equal_nan=True)
    assert base64.b64decode(encode_xy(np.arange(8.0).reshape(2, 4))) == np.arange(8, dtype="<f4").tobytes()
    assert encode_xy(np.zeros((0, 2))) == ""
    with pytest.raises(ValueError, match="N, 2"):
        encode_xy(np.zeros((3, 3)))


def test_frame_json_cannot_close_the_script_it_travels_in() -> None:
    text = frame_json({"items": [{"t": "text", "text": "</script><img src=x onerror=alert(1)>&amp;"}], "b": [np.float32(1.5), float("nan")]})
    assert "<" not in text and ">" not in text and "&" not in text
    assert json.loads(text) == {"items": [{"t": "text", "text": "</script><img src=x onerror=alert(1)>&amp;"}], "b": [1.5, None]}


class _Handle:
    def __init__(self, content: str = "") -> None:
        self.content = content
        self.visible = True
        self.removed = False
        self._impl = type("Impl", (), {"uuid": "u" * 32, "value": ""})()

    def on_update(self, fn) -> None:
        self.cb = fn

    def remove(self) -> None:
        self.removed = True


class FakeGui:
    """Records the elements a panel adds (what viser's GUI API would send)."""

    def __init__(self) -> None:
        self.htmls: list[_Handle] = []
        self.texts: list[_Handle] = []

    def add_html(self, content: str) -> _Handle:
        self.htmls.append(_Handle(content))
        return self.htmls[-1]

    def add_text(self, label: str, value: str) -> _Handle:
        self.texts.append(_Handle())
        return self.texts[-1]


FRAME = {"bounds": [0, 1, 0, 1], "aspect": "equal", "background": None, "title": "", "axes": None, "legend": [], "items": []}


def test_a_frame_is_sent_only_when_it_changes_and_at_most_at_the_rate() -> None:
    clock = FakeClock()
    gui = FakeGui()
    panel = Panel2D(gui, "p", height=200, max_rate=10.0, clock=clock)
    canvas, frame = gui.htmls
    assert 'data-key="p"' in canvas.content and "height:200px" in canvas.content
    assert panel.show(FRAME) and panel.sent == 1
    assert not panel.show(FRAME)  # the same frame: nothing sent
    moved = dict(FRAME, bounds=[0, 2, 0, 1])
    assert not panel.show(moved)  # too soon: kept ...
    clock.advance(0.05)
    assert not panel.flush()
    clock.advance(0.06)
    assert panel.flush() and panel.sent == 2  # ... and sent when its time came
    assert panel.last_frame["bounds"] == [0, 2, 0, 1]
    assert '"bounds":[0,2,0,1]' in frame.content


def test_events_reach_the_handler_in_order_and_replays_are_dropped() -> None:
    got: list = []
    clock = FakeClock()
    panel = Panel2D(FakeGui(), "p", on_event=got.append, clock=clock)
    panel.receive(msg(DRAG, s=1))
    panel.receive(msg(dict(DRAG, phase="release"), s=2))
    panel.receive(msg(dict(DRAG, phase="start"), s=2))  # a replay of seq 2
    panel.receive(msg(dict(DRAG, phase="start"), s=1))  # an old one
    assert [e["phase"] for e in got] == ["move", "release"]
    assert panel.dropped == 2


def test_events_over_the_rate_are_dropped() -> None:
    got: list = []
    clock = FakeClock()
    panel = Panel2D(FakeGui(), "p", on_event=got.append, clock=clock)
    key = {"k": "key", "key": "a", "phase": "down"}
    for s in range(1, 20):  # 19 x 24 = 456 events at once: a burst of 200 passes
        panel.receive(msg(*[key] * 24, s=s))
    assert len(got) == 200
    clock.advance(0.5)  # half a second refills half the burst
    panel.receive(msg(*[key] * 24, s=100))
    assert len(got) == 224


def test_a_handler_that_raises_does_not_stop_the_panel() -> None:
    calls: list = []

    def handler(ev):
        calls.append(ev)
        raise RuntimeError("boom")

    panel = Panel2D(FakeGui(), "p", on_event=handler)
    panel.receive(msg(DRAG, DRAG, s=1))
    assert len(calls) == 2


def test_the_engine_ships_with_the_package() -> None:
    from importlib import resources

    from ejsrl.view._panel2d import engine_js

    text = engine_js()
    assert "window.__ejs2d" in text and "fillText" in text and "innerHTML" not in text
    assert resources.files("ejsrl.view").joinpath("_panel2d.js").is_file()


def test_frames_at_the_rate_but_jittering_are_all_sent() -> None:
    """A lab at 60 frames/s ticks every 16.7 ms on average, some early: none is held back
    (a strict minimum interval sent about two frames in three)."""
    clock = FakeClock()
    panel = Panel2D(FakeGui(), "p", max_rate=60.0, clock=clock)
    for i in range(120):
        clock.advance(0.0150 if i % 2 else 0.0183)
        panel.show(dict(FRAME, bounds=[0, 1 + i, 0, 1]))
    assert panel.sent == 120
    for i in range(120):  # ... but twice the rate is held to it
        clock.advance(1 / 120)
        panel.show(dict(FRAME, bounds=[0, 1000 + i, 0, 1]))
    assert 60 <= panel.sent - 120 <= 62


def test_an_unlimited_rate_sends_every_new_frame() -> None:
    clock = FakeClock()
    panel = Panel2D(FakeGui(), "p", max_rate=float("inf"), clock=clock)
    for i in range(5):  # the same instant: a caller that rate-limits itself
        assert panel.show(dict(FRAME, bounds=[0, 1 + i, 0, 1]))
    assert panel.sent == 5


def test_a_panel_of_automatic_height_tells_the_engine_its_limits() -> None:
    from ejsrl.view._panel2d import AUTO_HEIGHT_RESERVE, AUTO_MIN_HEIGHT

    gui = FakeGui()
    Panel2D(gui, "auto", height=300, auto_height=True)
    Panel2D(gui, "fixed", height=340)
    auto, _f1, fixed, _f2 = gui.htmls
    assert f" data-auto-height={AUTO_MIN_HEIGHT},{AUTO_HEIGHT_RESERVE} " in auto.content
    assert " data-auto-height=" not in fixed.content and "height:340px" in fixed.content
