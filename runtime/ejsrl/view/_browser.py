"""Which browser a request comes from: the cookie that binds a classroom session to the
browser that created it (:mod:`ejsrl.app._sessions`).

The lab's page sets :data:`BROWSER_COOKIE` (random, ``HttpOnly``: the page's scripts
cannot read it; ``SameSite=Strict``: no other site's page sends it) when the request has
none; the websocket handshake then carries it, and :func:`browser_of` reads it there.
A page reached from another site (a link in a course page: ``Sec-Fetch-Site:
cross-site``) is sent without the cookie, as SameSite=Strict asks: it is given none then,
which would replace the browser's own. Its websocket, the page's own request, carries the
cookie; a browser's websocket that has none (its first visit came from another site) is
named on the handshake's response (:func:`name_browser`, :func:`handshake_cookie`).
"""

from __future__ import annotations

import re
import secrets
from typing import Any

__all__ = ["BROWSER_COOKIE", "browser_of", "name_browser", "page_cookie", "handshake_cookie"]

#: the cookie that names a browser (random, HttpOnly, SameSite=Strict): a session resumes
#: only in the browser that created it (see :mod:`ejsrl.app._sessions`)
BROWSER_COOKIE = "ejsrl_browser"
_COOKIE_VALUE = re.compile(r"[A-Za-z0-9_-]{16,64}")


def browser_of(server: Any, client_id: int) -> str | None:
    """The :data:`BROWSER_COOKIE` that client ``client_id``'s websocket handshake carried
    (its browser), or None (a script, or a browser that has not loaded the page)."""
    try:
        connection = server._websock_server._live_connections.get(client_id)
        headers = connection.request.headers if connection is not None and connection.request is not None else None
    except AttributeError:
        return None
    return _cookie(headers) if headers is not None else None


def _cookie(headers: Any) -> str | None:
    """The well-formed :data:`BROWSER_COOKIE` in request ``headers``, or None."""
    for line in headers.get_all("Cookie"):
        for part in line.split(";"):
            name, _, value = part.strip().partition("=")
            if name == BROWSER_COOKIE and _COOKIE_VALUE.fullmatch(value):
                return value
    return None


def _set_cookie(response: Any, value: str | None = None) -> None:
    """Name a browser (``value``, or a new random name) on ``response``."""
    value = value or secrets.token_urlsafe(18)
    response.headers["Set-Cookie"] = f"{BROWSER_COOKIE}={value}; Path=/; HttpOnly; SameSite=Strict"


def page_cookie(request: Any, response: Any) -> None:
    """Name the browser on the page's ``response`` if ``request`` carried no name and did
    not come from another site's page (which withholds a SameSite=Strict cookie)."""
    if _cookie(request.headers) is None and request.headers.get("Sec-Fetch-Site", "") != "cross-site":
        _set_cookie(response)


def name_browser(request: Any) -> None:
    """A browser's websocket handshake (it sends an ``Origin``) with no name: give it one,
    in the request (the session reads it there) and, by :func:`handshake_cookie`, in the
    response. A script's handshake (no ``Origin``) stays nameless."""
    if _cookie(request.headers) is None and request.headers.get("Origin"):
        value = secrets.token_urlsafe(18)
        request.headers["Cookie"] = f"{BROWSER_COOKIE}={value}"
        request._ejsrl_browser = value


def handshake_cookie(request: Any, response: Any) -> None:
    """Send the name :func:`name_browser` gave, on the handshake's response."""
    value = getattr(request, "_ejsrl_browser", None)
    if value is not None:
        _set_cookie(response, value)
