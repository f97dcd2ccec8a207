"""Which browser a request comes from: the cookie that binds a classroom session to the
browser that created it (:mod:`ejsrl.app._sessions`).

The lab's page sets :data:`BROWSER_COOKIE` (random, ``HttpOnly``: the page's scripts
cannot read it; ``SameSite=Strict``: no other site's page sends it) when the request has
none; the websocket handshake then carries it, and :func:`browser_of` reads it there.
"""

from __future__ import annotations

import re
import secrets
from typing import Any

__all__ = ["BROWSER_COOKIE", "browser_of"]

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


def _set_cookie(response: Any) -> None:
    """Name a browser that has no :data:`BROWSER_COOKIE` yet (on the page's response)."""
    response.headers["Set-Cookie"] = (f"{BROWSER_COOKIE}={secrets.token_urlsafe(18)}; Path=/; HttpOnly; "
                                      "SameSite=Strict")
