"""A visit of a lab's web page (``ejsgen build --web``) in Chromium, timed and weighed: shared by
the page tests (tests/web) and ``bench/web.py`` (which puts ``tests/`` on its path)."""

from __future__ import annotations

import time
from typing import Any, NamedTuple
from urllib.parse import urlsplit


class Visit(NamedTuple):
    """What a visit took: ``seconds`` until the panel could be used and ``received``, the bytes
    over the wire (every response's body and headers, the page's and its worker's)."""

    seconds: float
    received: int


def visit(page: Any, url: str, *, cold: bool, text: str | None = None, timeout_ms: int = 120_000,
          parts: dict[str, int] | None = None) -> Visit:
    """Open ``url`` in ``page`` (with an empty browser cache if ``cold``) until the panel's Play
    button is visible, and ``text`` too if given (a control's label); ``timeout_ms`` for Play.
    ``parts``, if given, gets the bytes received by each response's path under the site
    (``python/python.wasm.gz``; ``index.html`` for the page)."""
    responses: list[Any] = []

    def seen(response: Any) -> None:
        responses.append(response)

    page.on("response", seen)
    if cold:
        cdp = page.context.new_cdp_session(page)
        cdp.send("Network.clearBrowserCache")
        # and what the page keeps itself: its Cache Storage (the inflated python.wasm, with the
        # compiled code Chromium keeps beside it) and its service worker
        cdp.send("Storage.clearDataForOrigin", {"origin": url.split("/", 3)[0] + "//" + url.split("/", 3)[2],
                                                "storageTypes": "cache_storage,service_workers"})
        cdp.detach()
    start = time.monotonic()
    page.goto(url)
    page.get_by_role("button", name="Play").wait_for(state="visible", timeout=timeout_ms)
    if text is not None:
        page.get_by_text(text).first.wait_for(state="visible")
    took = time.monotonic() - start
    page.remove_listener("response", seen)
    received = 0
    for r in responses:
        sizes = r.request.sizes()
        body = 0 if r.request.method == "HEAD" else sizes["responseBodySize"]  # a HEAD reports the file's length
        received += body + sizes["responseHeadersSize"]
        if parts is not None:
            path = urlsplit(r.url).path.lstrip("/") or "index.html"
            parts[path] = parts.get(path, 0) + body + sizes["responseHeadersSize"]
    return Visit(took, received)
