"""Who may connect to a served app, and how large a message may be (ejsrl.view._guard).

Hostile raw clients: a page on another site (its Origin), a DNS-rebinding page (its Host),
a client sending frames far larger than the UI ever does; and the warning printed when
a lab is served to the network."""

from __future__ import annotations

import urllib.request

import http.client
import math

import pytest
import viser
from websockets.exceptions import InvalidStatus

import ejsrl.view._guard as guard_module
from ejsrl.app import main
from ejsrl.view._guard import MAX_MESSAGE_BYTES, VISER_TESTED, guard_of, parse_origin, start_server
from ejsrl.view.viser_view import ViserView, make_server
from testkit.guard_client import Client, gui_update, run_async
from testkit.view_lab import LabModel, make_app, make_view


def _run(coro):
    return run_async(coro)


def _refused(port: int, **kw) -> int:
    """The HTTP status of a refused websocket handshake (fails if it was accepted)."""

    async def attempt():
        try:
            client = await Client.open(port, camera=False, **kw)
        except InvalidStatus as exc:
            return exc.response.status_code
        await client.close()
        raise AssertionError(f"the handshake with {kw} was accepted")

    return _run(attempt())


def _get(port: int, host: str) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        conn.request("GET", "/", headers={"Host": host})
        response = conn.getresponse()
        return response.status, response.read()
    finally:
        conn.close()


def test_a_page_on_another_site_cannot_open_the_websocket(served, caplog):
    port = served.server.get_port()
    for origin in ("http://evil.example.com", "http://evil.example.com:%d" % port, "null",
                   "http://127.0.0.1:%d" % (port + 1),  # another local page (a dev server, a notebook)
                   "http://203.0.113.5:%d" % port,  # someone else's machine, on the lab's port
                   "https://127.0.0.1:%d" % port):
        assert _refused(port, origin=origin) == 403, origin
    assert served.server.get_clients() == {}
    # the terminal says what was refused and how to allow it, once per origin
    said = [r.getMessage() for r in caplog.records if r.name == "ejsrl.serve"]
    assert ("ejsrl: refused a connection: origin 'http://evil.example.com' is not this lab's page. If that page "
            "should reach the lab, start the lab with --allow-origin http://evil.example.com") in said
    assert len(said) == 6


def test_a_refused_page_changes_nothing(served):
    """The attack of the issue: a slider driven from http://evil.example.com."""
    length = served.view.panel.handles_by_label["Length"]._impl.uuid

    async def attack():
        try:
            evil = await Client.open(served.server.get_port(), origin="http://evil.example.com")
        except InvalidStatus:
            return
        await evil.send(gui_update(length, value=1.9))
        await evil.settle()
        await evil.close()

    _run(attack())
    assert served.app.model.L == 1.0


def test_the_lab_s_own_page_and_scripts_connect(served):
    port = served.server.get_port()
    length = served.view.panel.handles_by_label["Length"]._impl.uuid

    async def scenario():
        own = await Client.open(port, origin=f"http://127.0.0.1:{port}", server=served.server)
        by_name = await Client.open(port, origin=f"http://localhost:{port}", host=f"localhost:{port}",
                                    server=served.server)
        script = await Client.open(port, server=served.server)  # no Origin header: not a browser
        await script.send(gui_update(length, value=0.7))
        await own.until(lambda: own.values_of(length) == [0.7], "the page to be sent the script's value")
        for c in (own, by_name, script):
            await c.close()

    _run(scenario())
    assert served.app.model.L == 0.7


def test_a_dns_rebinding_page_is_refused(served):
    """evil.example.com resolving to 127.0.0.1: same origin for the browser, but not a name
    of this server."""
    port = served.server.get_port()
    assert _refused(port, origin=f"http://evil.example.com:{port}", host=f"evil.example.com:{port}") == 403
    status, body = _get(port, f"evil.example.com:{port}")
    assert status == 403 and b"unknown Host" in body
    status, body = _get(port, f"127.0.0.1:{port}")
    assert status == 200 and b"<html" in body.lower()


def test_allow_origin_widens_the_check():
    server, _ = make_server("127.0.0.1", 0, allow_origins=["https://labs.example.org"])
    try:
        port = server.get_port()

        async def scenario():
            proxied = await Client.open(port, origin="https://labs.example.org", host="labs.example.org")
            await proxied.close()

        _run(scenario())
        assert _refused(port, origin="http://evil.example.com") == 403
        assert _get(port, "labs.example.org")[0] == 200
    finally:
        server.stop()
    server, _ = make_server("127.0.0.1", 0, allow_origins=["*"])
    try:
        port = server.get_port()

        async def anyone():
            c = await Client.open(port, origin="http://evil.example.com", host="evil.example.com")
            await c.close()

        _run(anyone())
    finally:
        server.stop()


@pytest.mark.parametrize(("text", "expected"), [
    ("HTTP://Labs.Example.org:80", "http://labs.example.org"),
    ("https://labs.example.org:443/", "https://labs.example.org"),
    ("http://10.0.0.5:8080", "http://10.0.0.5:8080"),
    ("http://[::1]:8080", "http://[::1]:8080"),
    ("*", "*"),
])
def test_origins_are_normalized(text, expected):
    assert parse_origin(text) == expected


@pytest.mark.parametrize("text", ["labs.example.org", "ftp://labs.example.org", "http://labs.example.org/lab",
                                  "http://user@labs.example.org", "http://x:notaport"])
def test_a_malformed_allow_origin_is_an_error_with_an_example(text, capsys):
    status = main(LabModel, make_view(), sim=make_app().sim, meta=make_app().meta, base_dir=".",
                  argv=["--allow-origin", text])
    assert status == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --allow-origin:") and "http://lab.example.org:8080" in err


def test_an_oversized_frame_closes_only_that_connection(served):
    port = served.server.get_port()
    length = served.view.panel.handles_by_label["Length"]._impl.uuid

    async def scenario():
        big = await Client.open(port, server=served.server)
        other = await Client.open(port, server=served.server)
        await big.send(b"\x00" * (8 * 1024 * 1024))
        await Client.until(lambda: big.closed is not None, "the sender's connection to close")
        assert big.closed.rcvd.code == 1009  # "message too big"
        # the server is fine: the other client keeps working and new ones connect
        await other.send(gui_update(length, value=0.3))
        await Client.until(lambda: served.app.model.L == 0.3, "the other client's update")
        late = await Client.open(port, server=served.server)
        await late.close()
        await other.close()

    _run(scenario())


def test_the_cap_leaves_room_for_the_longest_value_the_ui_accepts(served):
    from ejsrl.view._validate import MAX_TEXT_LENGTH

    name = served.view.panel.handles_by_label["Name"]._impl.uuid
    longest = "é" * MAX_TEXT_LENGTH  # two bytes each in UTF-8
    assert len(longest.encode()) + 200 < MAX_MESSAGE_BYTES

    async def scenario():
        c = await Client.open(served.server.get_port(), server=served.server)
        await c.send(gui_update(name, value=longest))
        await Client.until(lambda: served.app.model.name == longest, "the long text to be applied")
        await c.close()

    _run(scenario())


def test_serving_on_every_interface_prints_a_warning(capsys):
    app = make_app()
    server = app.serve("0.0.0.0", 0, block=False)
    try:
        out, err = capsys.readouterr()
        assert "warning: --host 0.0.0.0 opens this lab to every network this machine is on" in err
        assert "Leave --host out (127.0.0.1)" in err
        port = server.get_port()
        # the addresses students type are printed, and the lab answers on each of them
        import socket

        hostname = socket.gethostname()
        addresses = {i[4][0] for i in socket.getaddrinfo(hostname, None, socket.AF_INET)} - {"127.0.0.1"}
        for name in [hostname, *addresses]:
            if name != "localhost" and not name.startswith("127."):
                assert f"http://{name}:{port}" in out
        for address in addresses:
            with urllib.request.urlopen(f"http://{address}:{port}/", timeout=10) as page:
                assert page.status == 200

        async def own_page():  # reached through the loopback address, the lab still works
            c = await Client.open(port, origin=f"http://127.0.0.1:{port}", server=server)
            await c.settle()  # the view's greeting (it sets the new client's camera) goes out first
            await c.close()

        _run(own_page())
        assert _refused(port, origin="http://evil.example.com") == 403
    finally:
        app.stop()
        server.stop()
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False)
    try:
        assert "warning" not in capsys.readouterr().err
    finally:
        app.stop()
        server.stop()


# -- the viser internals the guards hook -------------------------------------------------------------


def test_the_installed_viser_is_one_the_guards_were_tested_with():
    """Fails when viser is upgraded past the tested range: check the hooks (this file's
    tests), then add the version to VISER_TESTED and to pyproject's pin."""
    major_minor = ".".join(viser.__version__.split(".")[:2])
    assert major_minor in VISER_TESTED, f"viser {viser.__version__} is not in VISER_TESTED {VISER_TESTED}"


def test_a_viser_whose_internals_moved_is_refused_loudly(monkeypatch):
    monkeypatch.setattr(guard_module, "_VISER_HANDLER", "SomewhereElse.ws_handler")
    with pytest.raises(RuntimeError, match=r"ejsrl cannot guard viser .*viser>=1\.1,<1\.2"):
        start_server("127.0.0.1", 0)
    monkeypatch.undo()

    from viser.infra import _infra

    async def streaming_consumer(websocket, handle_message, message_class):
        async for raw in websocket.recv_streaming():
            handle_message(message_class.deserialize(raw))

    monkeypatch.setattr(_infra, "_message_consumer", streaming_consumer)
    with pytest.raises(RuntimeError, match="message consumer does not read with connection.recv"):
        start_server("127.0.0.1", 0)


def test_every_server_the_runtime_makes_is_guarded():
    app = make_app()
    server = app.serve("127.0.0.1", 0, block=False)
    try:
        guard = guard_of(server)
        assert guard is not None and guard.server is server
        # the view registered ejsgen's check for each of its controls
        view = next(v for v in app.views if isinstance(v, ViserView))
        assert {b.handle._impl.uuid for b in view.panel.controls} <= set(guard.checks)
        check = guard.checks[view.panel.handles_by_label["Length"]._impl.uuid]
        assert not check(math.nan).ok and check(5.0).value == 2.0
    finally:
        app.stop()
        server.stop()


def test_the_viser_pin_matches_the_tested_versions():
    import tomllib
    from pathlib import Path

    from ejsgen.generate import REQUIREMENTS

    root = Path(__file__).resolve().parents[2]
    deps = tomllib.loads((root / "pyproject.toml").read_text())["project"]["dependencies"]
    pin = f"viser>={VISER_TESTED[0]},<{VISER_TESTED[-1].split('.')[0]}.{int(VISER_TESTED[-1].split('.')[1]) + 1}"
    assert pin in deps and pin in REQUIREMENTS  # the package and every built app's requirements.txt
