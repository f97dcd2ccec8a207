"""An image element is shown when its page says that its panel is laid out (the probe's message
through a hidden text input), checked like any client message; a timer only as a fallback.

Through a raw websocket client speaking viser's wire format (what a hostile script could send),
against a served lab with an image element (testkit.image_lab); the browser test of console errors
(tests/browser/test_image_console.py) checks that a real page sends the message in time.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from testkit.browser import serving
from testkit.classroom import join
from testkit.guard_client import gui_update, run_async
from testkit.image_lab import CHANGING


@pytest.fixture
def served_image(tmp_path: Path):
    """``(app, port)``: testkit.image_lab's lab served with a simulation per tab; stopped after."""
    from ejsgen.cli import build

    spec = tmp_path / "picture.ejs.yaml"
    spec.write_text(CHANGING)
    with serving(build(spec, tmp_path / "app"), per_client=True, max_sessions=2, grace=5.0) as (app, url):
        yield app, int(url.rsplit(":", 1)[1])


def _binding(app):
    (session,) = app.classroom.sessions.values()
    (image,) = [im for view in session.app.views for im in view.panel.images]
    return image


def test_the_picture_is_shown_only_for_the_probes_exact_message(served_image) -> None:
    from ejsrl.view._image import IMAGE_SETTLE, LAID_OUT

    app, port = served_image

    async def scenario() -> None:
        client = await join(port)
        image = _binding(app)
        uuid = client.uuid_of("GuiTextMessage", "ejs image laid out")
        probe = next(m["uuid"] for m in client.seen("GuiHtmlMessage") if uuid in m["props"]["content"])
        picture = client.seen("GuiImageMessage")[0]
        assert picture["props"]["visible"] is False  # hidden until the page says its panel is laid out
        for wrong in ("laid-out ", "LAID-OUT", "<img src=x onerror=alert(1)>", "x" * 5000):
            await client.send(gui_update(uuid, value=wrong))
        await client.until(lambda: image.refused >= 3, "the wrong messages to be refused")
        await client.settle()
        assert not image.shown and image.shown_by is None
        await client.send(gui_update(uuid, value=LAID_OUT))
        await client.until(lambda: image.shown, "the picture to be shown")
        assert image.shown_by == "page"  # long before the fallback timer
        await client.until(lambda: client.seen("GuiUpdateMessage", uuid=picture["uuid"], updates={"visible": True}), "visible sent")
        # the probe and its input are taken out of the panel once they have done their job
        await client.until(lambda: {uuid, probe} <= {m["uuid"] for m in client.seen("GuiRemoveMessage")}, "the probe removed")
        await client.close()

    run_async(scenario())
    assert IMAGE_SETTLE >= 20.0  # the timer is only a fallback: a busy page reports within ~10 s


def test_a_page_that_never_reports_gets_its_picture_after_the_fallback() -> None:
    """With no message, :meth:`ImageBinding.update` shows the element once IMAGE_SETTLE is past
    (a page's Python has no timer thread); no picture is read before that."""
    import numpy as np
    from ejsrl.view import _image
    from ejsrl.view.elements import Image
    from ejsrl.view.viser_view import make_server
    from testkit.clock import FakeClock

    server, _url = make_server("127.0.0.1", 0)
    try:
        clock = FakeClock()
        picture = np.zeros((8, 8, 3), dtype=np.uint8)
        image = _image.ImageBinding(server.gui, Image(source="img"), clock=clock, first=lambda: (picture, None))
        assert not image.due() and not image.update(picture + 1, None) and not image.shown
        clock.advance(_image.IMAGE_SETTLE - 0.01)
        assert not image.due() and not image.shown
        clock.advance(0.02)
        assert image.due() and image.update(picture + 1, None)
        assert image.shown_by == "timer" and image.handle.visible and image.pushes == 1
    finally:
        server.stop()
