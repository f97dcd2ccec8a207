"""The control panel: initial values, values from the browser, per-frame refresh, errors."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.view._plot_frame import decode_xy

from ejsrl.view import _gui


class Client:
    """Stands in for a connected browser: records its notifications."""

    def __init__(self) -> None:
        self.notes: list[tuple[str, str, str]] = []

    def add_notification(self, title, body, *, color=None, auto_close_seconds=None, **_kw):
        self.notes.append((title, body, color))
        return Note(self, (title, body, color))


class Note:
    def __init__(self, client, note):
        self.client, self.note = client, note

    def remove(self):
        self.client.notes.remove(self.note)


def binding(served, bind: str):
    return next(b for b in served.view.panel.controls if b.control.bind == bind)


def connect(served, monkeypatch) -> Client:
    client = Client()
    monkeypatch.setattr(served.server, "get_clients", lambda: {1: client})
    return client


def test_controls_start_at_the_model_values(served):
    p = served.view.panel
    assert binding(served, "L").handle.value == pytest.approx(1.0)
    assert binding(served, "L").handle.label == "Length"
    assert binding(served, "n").handle.value == 3
    assert binding(served, "on").handle.value is True
    assert binding(served, "name").handle.value == "lab"
    assert binding(served, "mode").handle.value == "fast"
    assert binding(served, "mode").handle.options == ("slow", "fast")
    assert binding(served, "q[1]").handle.value == pytest.approx(0.5)
    assert p.play_button.label == "Play"
    assert set(p.buttons) == {"Double L"}
    assert len(p.plots) == 1 and len(p.images) == 1 and len(p.labels) == 1


def test_a_browser_value_is_clamped_then_applied(served):
    b = binding(served, "L")
    served.view.panel.set_from_client(b, 7.5, Client())
    assert served.app.model.L == pytest.approx(2.0)
    assert b.handle.value == pytest.approx(2.0)  # the panel shows the clamped value
    assert served.app.model.x == pytest.approx(0.0)  # fixed relations ran: x = L sin(0)


def test_an_array_element_control_writes_that_element(served):
    served.view.panel.set_from_client(binding(served, "q[1]"), -0.25, Client())
    assert served.app.model.q.tolist() == [0.0, -0.25, 1.0]


def test_a_refused_value_is_not_applied_and_the_user_is_told(served):
    client = Client()
    b = binding(served, "n")
    served.view.panel.set_from_client(b, float("nan"), client)
    assert served.app.model.n == 3
    assert b.handle.value == 3  # put back
    assert client.notes and client.notes[0][2] == "red" and "Count" in client.notes[0][1]


def test_an_unknown_dropdown_option_is_refused(served):
    client = Client()
    served.view.panel.set_from_client(binding(served, "mode"), "warp", client)
    assert served.app.model.mode == "fast" and client.notes


def test_model_changes_reach_the_controls_every_frame(served):
    served.app.model.L = 0.5
    served.app.model.name = "changed"
    served.app.frame()
    assert binding(served, "L").handle.value == pytest.approx(0.5)
    assert binding(served, "name").handle.value == "changed"


def test_a_control_the_user_just_moved_is_not_overwritten(served):
    b = binding(served, "L")
    served.view.panel.set_from_client(b, 1.5, Client())
    served.app.model.L = 0.3  # the simulation changes it right away
    served.app.frame()
    assert b.handle.value == pytest.approx(1.5)
    served.clock.advance(_gui.USER_HOLD_SECONDS - 0.01)
    served.app.frame()
    assert b.handle.value == pytest.approx(1.5)  # still held
    served.clock.advance(0.02)  # the hold is over
    served.app.frame()
    assert b.handle.value == pytest.approx(0.3)


def test_unchanged_values_are_not_resent(served):
    served.app.frame()
    served.sent.clear()
    served.app.frame()  # paused, nothing changed
    assert served.messages("GuiUpdateMessage") == []


def test_label_text_is_interpolated_each_frame(served):
    served.app.model.L = 2.0
    served.app.play()
    for _ in range(3):
        served.app.frame()
    label = served.view.panel.labels[0][1]
    assert label.content == f"x = {served.app.model.x:.3f}"
    assert served.view.panel.readout.content == "**t** = 0.3"


def test_buttons_run_their_action(served):
    served.view.panel.buttons["Double L"]._impl.update_cb[0](None)
    assert served.app.model.L == pytest.approx(2.0)


def test_play_step_reset(served):
    p = served.view.panel
    p.play_button._impl.update_cb[0](None)
    assert served.app.is_playing()
    served.app.frame()
    assert p.play_button.label == "Pause"
    p.play_button._impl.update_cb[0](None)
    assert not served.app.is_playing()
    p.step_button._impl.update_cb[0](None)
    assert served.app.model.t == pytest.approx(0.2)
    p.reset_button._impl.update_cb[0](None)
    assert served.app.model.t == 0.0


def test_plots_append_one_point_a_frame_within_the_window(served):
    served.app.play()
    for _ in range(30):
        served.app.frame()
    plot = served.view.panel.plots[0]
    plot.push(force=True)
    frame = plot.handle.last_frame  # what the browser draws
    lines = [it for it in frame["items"] if it["t"] == "polyline"]
    assert [it["stroke"] for it in lines] == ["rgb(255, 0, 0)", "#ff7f0e"]  # its colour, then the palette's
    xy = decode_xy(lines[0]["xy"], 2)
    x, y = xy[:, 0], xy[:, 1]
    assert x[-1] == pytest.approx(3.0)
    assert x[0] >= 3.0 - 2.0 - 1e-6  # window 2.0
    assert np.allclose(y, np.sin(x), atol=1e-6) and np.allclose(decode_xy(lines[1]["xy"], 2)[:, 1], 1.0)
    assert frame["bounds"][1] - frame["bounds"][0] == pytest.approx(2.0)  # the x axis is the window
    served.app.reset()
    assert not [it for it in plot.handle.last_frame["items"] if it["t"] == "polyline"]


def test_plot_pushes_are_throttled_while_playing(served):
    served.app.play()
    served.app.frame()
    before = len(served.messages("GuiUpdateMessage"))
    for _ in range(10):
        served.app.frame()  # all within far less than 1/15 s
    frames = {p.handle.frame._impl.uuid for p in served.view.panel.plots}
    pushes = [m for m in served.messages("GuiUpdateMessage")[before:] if m.uuid in frames]
    assert len(pushes) <= 2


def test_images_are_sent_only_when_they_change(served):
    im = served.view.panel.images[0]
    served.app.frame()
    assert im.pushes == 0  # the element was made with the lab's first picture: nothing to send
    assert im.handle.image.shape == (24, 32, 3)
    assert tuple(im.handle.image[6, 5 + 2]) != (60, 60, 60)  # the marker is drawn over it
    # (hidden until the client has laid its panel out, IMAGE_SETTLE on a wall-clock timer: the
    # browser test of console errors checks that; here the fixture may take longer than that)
    from ejsrl.view._plots import IMAGE_SETTLE

    served.clock.advance(IMAGE_SETTLE + 0.1)  # past that, and the rate limit (20 a second)
    served.app.frame()
    assert im.pushes == 0 and im.handle.visible
    served.app.model.n = 5
    served.clock.advance(0.06)
    served.app.frame()
    assert im.pushes == 1


@pytest.mark.parametrize("served", [{"autoplay": True}], indirect=True)
def test_a_lab_that_plays_from_the_start_shows_pause_in_the_pause_colour(served):
    p = served.view.panel
    assert served.app.is_playing()
    assert (p.play_button.label, p.play_button.color) == ("Pause", "orange")  # (it was green: the Play colour)
    p.play_button._impl.update_cb[0](None)
    served.app.frame()
    assert (p.play_button.label, p.play_button.color) == ("Play", "green")


@pytest.mark.parametrize("served", [{"controls": False}], indirect=True)
def test_the_control_bar_can_be_left_out(served):
    assert served.view.panel.play_button is None


def test_errors_in_user_code_are_shown_and_cleared_on_reset(served, monkeypatch):
    client = connect(served, monkeypatch)
    app = served.app
    # a label that calls ratio() (1 / (k - 1), with k == 1) once the simulation runs
    from ejsrl.view.elements import Dynamic, Label

    served.view.panel.labels.append((Label(Dynamic(lambda m: m.ratio() if m.t > 0 else 0, "ratio()"), where="lab.ejs.yaml:50:9"),
                                     served.server.gui.add_markdown("")))
    app.play()
    app.frame()
    assert app.error is not None and not app.is_playing()
    box = served.view.panel.error_box
    assert box.visible
    assert "lab.ejs.yaml:50:9" in box.content and "ZeroDivisionError" in box.content
    assert any(color == "red" and "lab.ejs.yaml:50:9" in title for title, _, color in client.notes)
    app.reset()
    app.frame()
    assert app.error is None and not box.visible
    assert not any(color == "red" for _, _, color in client.notes)  # the error notification is closed


def test_error_text_is_escaped(served, monkeypatch):
    connect(served, monkeypatch)
    from types import SimpleNamespace

    served.app.error = SimpleNamespace(message="<script>alert(1)</script>", where="x:1:1")
    served.app.error_rev += 1
    served.app.frame()
    assert "<script>" not in served.view.panel.error_box.content


def test_alerts_become_notifications(served, monkeypatch):
    client = connect(served, monkeypatch)
    served.app.model.alert("Target reached")
    served.app.frame()
    assert ("Alert", "Target reached", "yellow") in client.notes


def test_text_being_typed_is_not_overwritten_while_the_model_keeps_its_value(served):
    """A number field the user is typing into (its handle differs from the model, e.g. a
    half-typed value the server has not applied) is left alone after the hold expires, as
    long as the model's value does not move; when the model moves, the field follows."""
    b = binding(served, "L")
    served.app.frame()
    b.handle._impl.value = 0.3  # the browser's in-progress text, not applied to the model
    b.user_time = served.clock() - _gui.USER_HOLD_SECONDS - 1.0  # long after the last keystroke
    served.app.frame()
    assert b.handle.value == pytest.approx(0.3)
    served.app.model.L = 0.7  # now the model itself changes
    served.app.frame()
    assert b.handle.value == pytest.approx(0.7)


def test_the_readout_says_the_server_is_busy_only_below_the_labs_own_rate(served):
    """A tab shown 10 frames a second: held back for a lab that asks 30, not for one that asks
    10 (the trial's lab at ``fps: 10`` read 'showing 10 frames/s (the server is busy)')."""
    panel = served.view.panel
    served.app.play()
    served.app.shown_fps = 10.0
    served.app.frame()
    assert "showing 10 frames/s" in panel._readout_shown
    served.app.sim.fps = 10.0
    served.app.frame()
    assert "frames/s" not in panel._readout_shown and "busy" not in panel._readout_shown
    served.app.shown_fps = 6.0  # and below the lab's own 10, it is held back again
    served.app.frame()
    assert "showing 6 frames/s" in panel._readout_shown


def test_a_lab_that_fails_to_start_shows_its_controls_spec_values(tmp_path):
    """Its init raised: the error is shown, and a slider shows the value its variable was given in
    the spec (42), not its minimum (the trial's sliders at -180 and -140)."""
    from ejsgen.cli import build
    from ejsrl.app import load_app
    from ejsrl.view.viser_view import ViserView, make_server

    spec = tmp_path / "f.ejs.yaml"
    spec.write_text("ejs: 1\ntitle: Fails at start\nmodel:\n  variables:\n    t: 0.0\n    a: {value: 42.0}\n"
                    "  init: |\n    x = 1 / 0\n  evolution:\n    - code: t = t + 0.1\n"
                    "view:\n  - slider: {bind: a, min: -100, max: 100, label: A}\n")
    app = load_app(build(spec, tmp_path / "app"))
    assert app.error is not None and "ZeroDivisionError" in app.error.message
    server, _url = make_server("127.0.0.1", 0)
    try:
        view = ViserView(app, server)
        assert view.panel.controls[0].handle.value == 42.0
    finally:
        server.stop()
