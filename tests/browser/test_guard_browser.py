"""The issue's attack in a real browser: a page from another site opens the lab's websocket
and moves its slider. The same script run from the lab's own page does move it, so the
refusal comes from the origin check and nothing else.

The attacking page is served by another local web server (any other server on the
machine: a notebook, a dev server, a page a student saved): Chromium 156 already keeps
public sites such as http://evil.example.com away from loopback addresses on its own
(Local Network Access), other browsers do not, and local pages pass that check.
"""

from __future__ import annotations

import http.server
import threading

import pytest
import viser

from testkit.browser import wait_until
from testkit.browser_lab import make_app
from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.sim.model import ModelBase
from ejsrl.view._validate import MAX_TEXT_LENGTH
from ejsrl.view.elements import Text

#: opens the lab's websocket like viser's client does (subprotocol, msgpack, the camera
#: message that registers a client), then sets the control UUID to VALUE; resolves to
#: "sent" or to how the connection failed
ATTACK = """
([url, protocol, uuid, value]) => new Promise((resolve) => {
  const bytes = [];
  const enc = (v) => {
    if (typeof v === "number") {
      const b = new DataView(new ArrayBuffer(8)); b.setFloat64(0, v);
      bytes.push(0xcb, ...new Uint8Array(b.buffer));
    } else if (typeof v === "string") {
      const u = new TextEncoder().encode(v); bytes.push(0xd9, u.length, ...u);
    } else if (Array.isArray(v)) {
      bytes.push(0x90 | v.length); v.forEach(enc);
    } else {
      const keys = Object.keys(v); bytes.push(0x80 | keys.length);
      keys.forEach((k) => { enc(k); enc(v[k]); });
    }
  };
  const pack = (v) => { bytes.length = 0; enc(v); return new Uint8Array(bytes); };
  const ws = new WebSocket(url, [protocol]);
  ws.onopen = () => {
    ws.send(pack({type: "ViewerCameraMessage", wxyz: [1, 0, 0, 0], position: [3, 3, 3], fov: 1.3, near: 0.01,
                  far: 1000, image_height: 600, image_width: 800, look_at: [0, 0, 0], up_direction: [0, 0, 1]}));
    setTimeout(() => { ws.send(pack({type: "GuiUpdateMessage", uuid: uuid, updates: {value: value}})); }, 300);
    setTimeout(() => { ws.close(); resolve("sent"); }, 1500);
  };
  ws.onclose = (e) => resolve("closed " + e.code);
})
"""


@pytest.fixture
def served_app():
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False)
    yield app, server
    app.stop()
    server.stop()


class _EvilPage(http.server.BaseHTTPRequestHandler):
    def do_GET(self) -> None:  # noqa: N802 - http.server's name
        body = b"<html><body><h1>Free robots</h1></body></html>"
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: object) -> None:
        pass


@pytest.fixture
def evil_site():
    site = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _EvilPage)
    thread = threading.Thread(target=site.serve_forever, daemon=True)
    thread.start()
    yield f"http://localhost:{site.server_port}/"
    site.shutdown()
    thread.join(5)


@pytest.mark.browser
def test_a_page_on_another_site_cannot_drive_the_lab(served_app, evil_site, page):
    app, server = served_app
    port = server.get_port()
    uuid = app.views[0].panel.handles_by_label["Length"]._impl.uuid
    args = [f"ws://127.0.0.1:{port}/", f"viser-v{viser.__version__}", uuid]

    page.goto(evil_site)
    page.get_by_text("Free robots").wait_for()
    outcome = page.evaluate(ATTACK, [*args, 1.9])
    assert outcome.startswith("closed"), outcome  # the handshake was refused (403)
    assert app.model.L == 1.0 and server.get_clients() == {}

    # the same script from the lab's own page gets through: the check is the origin
    page.goto(f"http://127.0.0.1:{port}/")
    assert page.evaluate(ATTACK, [*args, 1.9]) == "sent"
    wait_until(lambda: abs(app.model.L - 1.9) < 1e-12, what="L == 1.9 from the lab's own page")


class _Notes(ModelBase):
    SPEC = "notes.ejs.yaml"
    VARIABLES = {"t": "float", "note": "str"}
    INDEPENDENT = "t"

    def _declare(self) -> None:
        self.t = 0.0
        self.note = "hello"

    def _evolution(self) -> list:
        return []


@pytest.mark.browser
def test_a_refused_value_is_explained_and_the_field_shows_the_lab_s_value(page):
    """A text over the limit typed in the real UI: refused before viser stores or
    broadcasts it, the notification says why, and the field shows the lab's text again."""
    app = App(_Notes, [Text("note", lambda m: m.note, lambda m, v: setattr(m, "note", v), label="Note", vtype="str")],
              sim=SimConfig(fps=30.0), meta=AppMeta(title="Notes"))
    server = app.serve("127.0.0.1", 0, block=False)
    broadcast: list = []  # what the server sent to every browser
    queue = server._websock_server.queue_message
    server._websock_server.queue_message = lambda m: (broadcast.append(m), queue(m))[1]
    try:
        page.goto(f"http://127.0.0.1:{server.get_port()}/")
        field = page.get_by_role("textbox").first
        field.wait_for(timeout=45_000)
        wait_until(lambda: field.input_value() == "hello", what="the field to show the lab's text")
        wait_until(lambda: len(server.get_clients()) == 1, what="the browser to be registered")
        field.fill("short and fine")
        wait_until(lambda: app.model.note == "short and fine", what="an ordinary text to reach the model")
        field.fill("x" * (MAX_TEXT_LENGTH + 1))
        note = page.locator(".mantine-Notification-title", has_text="Value refused")
        note.wait_for()
        assert f"at most {MAX_TEXT_LENGTH}" in page.locator(".mantine-Notification-root", has=note).inner_text()
        wait_until(lambda: field.input_value() == "short and fine", what="the field to show the lab's text again")
        assert app.model.note == "short and fine"
        # and the other browsers were never sent it (viser used to broadcast it before ejsgen refused it)
        sent = [m.updates.get("value") for m in broadcast if type(m).__name__ == "GuiUpdateMessage"]
        assert "short and fine" in sent and not any(isinstance(v, str) and len(v) > MAX_TEXT_LENGTH for v in sent)
    finally:
        app.stop()
        server.stop()
