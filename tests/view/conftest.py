from __future__ import annotations

import pytest

from ejsrl.view.viser_view import ViserView, make_server
from testkit.clock import FakeClock
from testkit.view_lab import make_app


class Served:
    """An app, its viser server and view, driven frame by frame by the test (no loop thread),
    on a clock that moves only when the test advances it (``served.clock.advance(dt)``)."""

    def __init__(self, app, server, view, clock: FakeClock) -> None:
        self.clock = clock
        self.app = app
        self.server = server
        self.view = view
        self.sent: list = []
        self._queue = server._websock_server.queue_message

        def counting(message):
            self.sent.append(message)
            return self._queue(message)

        server._websock_server.queue_message = counting

    def messages(self, kind: str | None = None) -> list:
        return [m for m in self.sent if kind is None or type(m).__name__ == kind]


@pytest.fixture
def served(request):
    kw = getattr(request, "param", {}) or {}
    clock = FakeClock()
    app = make_app(clock=clock, **kw)
    server, _url = make_server("127.0.0.1", 0)
    view = ViserView(app, server)
    app.views.append(view)
    yield Served(app, server, view, clock)
    server.stop()
