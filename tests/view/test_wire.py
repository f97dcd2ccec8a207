"""The view's fast per-frame writes (ejsrl.view._wire) send what viser's own setters send.

Each write is done twice on twin handles, once with ``handle.prop = value`` (viser's
path) and once through ``_wire``; the messages queued and the state kept must be the same,
value by value, including the writes viser skips because nothing changed.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ejsrl.view import _wire
from ejsrl.view.viser_view import make_server


@pytest.fixture
def server():
    srv, _url = make_server("127.0.0.1", 0)
    sent: list[Any] = []
    queue = srv._websock_server.queue_message

    def recording(message: Any) -> None:
        sent.append(message)
        queue(message)

    srv._websock_server.queue_message = recording
    srv.sent = sent
    yield srv
    srv.stop()


def _wire_form(message: Any, own_name: str) -> dict[str, Any]:
    """A message's fields as they go over the wire, with the twin's own name blanked."""
    out: dict[str, Any] = {"type": type(message).__name__}
    for k, v in vars(message).items():
        if k.startswith("_"):
            continue
        if v == own_name:
            v = "<node>"
        if isinstance(v, dict):
            v = {kk: (vv.tolist(), str(vv.dtype)) if isinstance(vv, np.ndarray) else
                 tuple((x.tolist(), str(x.dtype)) for x in vv) if isinstance(vv, tuple) and vv and isinstance(vv[0], np.ndarray)
                 else vv for kk, vv in v.items()}
        elif isinstance(v, tuple):
            v = tuple(float(x) for x in v)
        out[k] = v
    return out


def _twins(server: Any, make: Any, own: Any, writes: list[Any], viser_write: Any, fast_write: Any) -> None:
    a, b = make("/a"), make("/b")
    for value in writes:
        server.sent.clear()
        viser_write(a, value)
        via_viser = [_wire_form(m, own(a)) for m in server.sent]
        server.sent.clear()
        fast_write(b, value)
        via_wire = [_wire_form(m, own(b)) for m in server.sent]
        assert via_wire == via_viser, f"writing {value!r}"


POSITIONS = [(1.0, 2.0, 3.0), (1.0, 2.0, 3.0), np.array([1.0, 2.0, 3.0 + 1e-12]), np.array([0.5, -2.0, 7.0]),
             [0.5, -2.0, 7.000001], (math.inf, 0.0, 0.0), (math.inf, 0.0, 0.0), (math.nan, 0.0, 0.0), (0.0, 0.0, 0.0)]


def test_a_node_position_is_sent_as_viser_sends_it(server):
    _twins(server, lambda n: server.scene.add_frame(n, show_axes=False), lambda h: h.name, POSITIONS,
           lambda h, v: setattr(h, "position", v), _wire.set_position)


def test_a_node_orientation_is_sent_as_viser_sends_it(server):
    s = math.sqrt(0.5)
    writes = [(1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0), np.array([s, s, 0.0, 0.0]), (s, s, 0.0, 0.0), (s, 0.0, s, 0.0)]
    _twins(server, lambda n: server.scene.add_frame(n, show_axes=False), lambda h: h.name, writes,
           lambda h, v: setattr(h, "wxyz", v), _wire.set_wxyz)


def test_a_wrong_length_pose_is_refused_like_viser(server):
    frame = server.scene.add_frame("/f", show_axes=False)
    for bad in ((1.0, 2.0), np.zeros(4)):
        with pytest.raises(ValueError):
            frame.position = bad
        with pytest.raises(ValueError):
            _wire.set_position(frame, bad)


def test_line_points_are_sent_as_viser_sends_them(server):
    seg = np.zeros((1, 2, 3), dtype=np.float32)
    moved = np.array([[[0, 0, 0], [1, 0, -1]]], dtype=np.float64)
    longer = np.array([[[0, 0, 0], [1, 0, -1]], [[1, 0, -1], [2, 0, 0]]], dtype=np.float32)
    writes = [seg, seg.copy(), moved, moved.copy(), longer, longer]
    _twins(server, lambda n: server.scene.add_line_segments(n, points=seg, colors=(255, 0, 0)), lambda h: h.name, writes,
           lambda h, v: setattr(h, "points", v), lambda h, v: _wire.set_prop(h, "points", v))
    a, b = server.scene.add_line_segments("/c", points=seg, colors=(255, 0, 0)), server.scene.add_line_segments("/d", points=seg, colors=(255, 0, 0))
    a.points, b_value = longer, longer.copy()
    _wire.set_prop(b, "points", b_value)
    b_value[:] = 9.0  # the caller reuses its buffer: what was stored and sent must not change
    assert np.array_equal(a.points, b.points)


def test_scalar_and_colour_props_are_sent_as_viser_sends_them(server):
    _twins(server, lambda n: server.scene.add_line_segments(n, points=np.zeros((1, 2, 3), np.float32), colors=(0, 0, 0)),
           lambda h: h.name, [2.0, 2.0, 3.5, 1], lambda h, v: setattr(h, "thickness", v),
           lambda h, v: _wire.set_prop(h, "thickness", v))
    _twins(server, lambda n: server.scene.add_line_segments(n, points=np.zeros((1, 2, 3), np.float32), colors=(0, 0, 0)),
           lambda h: h.name, [np.array([255, 0, 0], np.uint8), np.array([255, 0, 0], np.uint8), np.array([0, 10, 20], np.uint8)],
           lambda h, v: setattr(h, "colors", v), lambda h, v: _wire.set_prop(h, "colors", v))


def test_markdown_is_sent_as_viser_sends_it(server):
    texts = ["**t** = 0", "**t** = 0", "**t** = 0.1", "Energy: 1.000 J", "<b>x</b> & y"]
    _twins(server, lambda n: server.gui.add_markdown(""), lambda h: h._impl.uuid, texts,
           lambda h, v: setattr(h, "content", v), _wire.set_markdown)
    md = server.gui.add_markdown("", image_root=Path(__file__).parent)  # (without a root viser warns, even of a data URL)
    _wire.set_markdown(md, "a ![img](data:image/png;base64,AAAA)")  # images go through viser's own path
    assert md.content == "a ![img](data:image/png;base64,AAAA)"


def test_plot_data_is_sent_as_viser_sends_it(server):
    x = np.linspace(0, 1, 5)
    writes = [(x, np.sin(x)), (x, np.sin(x)), (x.astype(np.float32), np.cos(x)), (x[:3], x[:3] ** 2)]
    _twins(server, lambda n: server.gui.add_uplot(data=(x, x), series=({"label": "t"}, {"label": "y"})),
           lambda h: h._impl.uuid, writes, lambda h, v: setattr(h, "data", v), lambda h, v: _wire.set_prop(h, "data", v))


def test_a_removed_handle_refuses_writes_like_viser(server):
    md = server.gui.add_markdown("x")
    frame = server.scene.add_line_segments("/gone", points=np.zeros((1, 2, 3), np.float32), colors=(0, 0, 0))
    md.remove()
    frame.remove()
    with pytest.raises(RuntimeError):
        _wire.set_markdown(md, "y")
    with pytest.raises(RuntimeError):
        _wire.set_prop(frame, "points", np.ones((1, 2, 3)))
