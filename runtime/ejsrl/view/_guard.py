"""Transport security of a served app: who may connect, how large a message may be, and
what a browser may change.

viser serves the page and the websocket on one port and trusts its clients: any page on
the web could open a websocket to ``ws://127.0.0.1:8080`` and drive the lab, a client
could switch a control off for everyone (``{"removed": true}``), broadcast ``NaN`` to the
other clients before ejsgen saw it, or send 50 MB frames. :func:`start_server` starts a
viser server with three guards in front of it:

- **Who may connect.** A request whose ``Host`` header is not a name of this server is
  refused (403; this stops DNS rebinding), and so is a websocket handshake whose
  ``Origin`` is not the page's own (``http://`` + the ``Host`` it connected to) nor one
  given with ``--allow-origin``. A handshake without an ``Origin`` header (a script, not
  a browser) is allowed: browsers always send one, and a script can forge any, so the
  check protects browsers only; the message guard below protects against scripts.
- **How large.** Incoming messages are capped at :data:`MAX_MESSAGE_BYTES`; a larger one
  closes that client's connection (code 1009) before its payload is read.
- **What a client may send.** Every incoming message is checked before viser decodes it:
  only the kinds the UI sends are let through (the viewer camera, a control's new
  ``value``, a gizmo drag), each with its fields checked and rebuilt; a control's value
  is validated, clamped and typed by ejsgen's own rules before viser stores or
  broadcasts it. A refused value is dropped, that client is told why and its control
  shows the server's value again. Everything else (file uploads, scene clicks, other
  properties of a control, requests for a public share link, whose button is hidden) is
  dropped.
- **How much.** Each client's messages are paced and coalesced (:mod:`ejsrl.view._fair`):
  a flood of values costs the server what a student dragging a slider costs. At most
  :data:`ejsrl.view._fair.MAX_PER_ADDRESS` websockets are open from one address (more get
  HTTP 429), and a websocket that has not registered within
  :data:`ejsrl.view._fair.REGISTER_SECONDS` is closed. Refusals and dropped messages are
  logged once per kind (:class:`ejsrl.view._fair.QuietLog`), never a line per message.

The checks of what a client sends are :mod:`ejsrl.view._inbound`'s; this module starts the
server with them and decides who may connect.

This relies on viser internals (see :data:`VISER_TESTED`); :func:`start_server` raises
if the hooks are not where it expects them, rather than serving without the guards.
"""

from __future__ import annotations

import asyncio
import contextlib
import http
import io
import ipaddress
import logging
import re
import socket
import threading
import weakref
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlsplit

from ejsrl.view import _fair
from ejsrl.view._browser import BROWSER_COOKIE, browser_of, handshake_cookie, name_browser, page_cookie
from ejsrl.view._inbound import (  # noqa: F401 - what a client may send; re-exported here
    _GIZMO_MESSAGES, MAX_COORDINATE, Check, MessageGuard, Notify, Verdict, generic_check,
)

__all__ = [
    "MAX_MESSAGE_BYTES",
    "VISER_TESTED",
    "Access",
    "MessageGuard",
    "Verdict",
    "parse_origin",
    "start_server",
    "guard_of",
    "is_loopback",
    "SESSION_PATH",
    "session_token",
    "browser_of",
    "BROWSER_COOKIE",
]

log = logging.getLogger("ejsrl.serve")

#: the largest message a client may send, in bytes: the UI's messages are a few hundred
#: bytes; the longest is a text field's value (at most 10,000 characters, 40 kB in UTF-8)
MAX_MESSAGE_BYTES = 64 * 1024

#: the viser versions whose internals this module hooks (``major.minor``)
VISER_TESTED = ("1.1",)

#: the name of viser's connection handler, to find its call of ``serve``
_VISER_HANDLER = "WebsockServer._background_worker.<locals>.ws_handler"

_WILDCARD_HOSTS = ("0.0.0.0", "", "::")

#: a tab's own address, ``/s/<token>`` (see :mod:`ejsrl.app._sessions`): the page is the
#: lab's page, and its websocket's path carries the token, so that a reload of the tab
#: finds its simulation again
SESSION_PATH = re.compile(r"/s/([A-Za-z0-9_-]{8,64})/?")



# -- who may connect ---------------------------------------------------------------------------


def parse_origin(text: str) -> str:
    """``text`` as a normalized origin (``scheme://host[:port]``, lower case, no default port).

    Raises ``ValueError`` with a message for the user if it is not an http(s) origin.
    """
    raw = text.strip()
    if raw == "*":
        return raw
    example = "an origin such as http://lab.example.org:8080"
    try:
        parts = urlsplit(raw)
        port = parts.port
    except ValueError:
        raise ValueError(f"--allow-origin: {text!r} is not {example}") from None
    if parts.scheme.lower() not in ("http", "https") or not parts.hostname:
        raise ValueError(f"--allow-origin: {text!r} is not {example} (scheme http or https, then a host)")
    if parts.path not in ("", "/") or parts.query or parts.fragment or parts.username or parts.password:
        raise ValueError(f"--allow-origin: {text!r} has more than scheme://host[:port]; write {example}")
    return _origin(parts.scheme.lower(), parts.hostname.lower(), port)


def _origin(scheme: str, host: str, port: int | None) -> str:
    default = 443 if scheme == "https" else 80
    shown = f"[{host}]" if ":" in host else host
    return f"{scheme}://{shown}" if port in (None, default) else f"{scheme}://{shown}:{port}"


def _split_host(value: str) -> tuple[str, int | None] | None:
    """A ``Host`` header as ``(hostname, port or None)``, or None if malformed."""
    try:
        parts = urlsplit("//" + value.strip())
        port = parts.port
    except ValueError:
        return None
    if not parts.hostname or parts.path or parts.username:
        return None
    return parts.hostname.lower(), port


def _is_ip(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
    except ValueError:
        return False
    return True


def is_loopback(host: str) -> bool:
    """True if binding ``host`` keeps the server on this machine."""
    if host in ("localhost",):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass
class Access:
    """Which ``Host`` headers and websocket ``Origin`` headers a server accepts.

    ``bind``: the address the server binds; ``allow_origins``: extra origins (``*``: any
    origin and any host, for a proxy you trust).
    """

    bind: str
    allow_origins: Sequence[str] = ()
    names: set[str] = field(init=False)
    origins: set[str] = field(init=False)
    anything: bool = field(init=False)

    def __post_init__(self) -> None:
        self.origins = {parse_origin(o) for o in self.allow_origins}
        self.anything = "*" in self.origins
        self.origins.discard("*")
        names = {"localhost"}
        if self.bind in _WILDCARD_HOSTS:
            try:
                host = socket.gethostname().lower()
                names |= {host, f"{host}.local", socket.getfqdn().lower()}
            except OSError:  # pragma: no cover - no hostname
                pass
        elif self.bind:
            names.add(self.bind.strip("[]").lower())
        for origin in self.origins:
            hostname = urlsplit(origin).hostname
            if hostname:
                names.add(hostname)
        self.names = names

    def host_ok(self, hostname: str) -> bool:
        """A name this server answers to: its own names, any IP address (a DNS rebinding
        attack needs a name it controls) and the hosts of the allowed origins."""
        return self.anything or hostname in self.names or hostname.endswith(".localhost") or _is_ip(hostname)

    def refusal(self, headers: Any) -> str | None:
        """Why a request with these headers is refused, or None to let it through."""
        if self.anything:
            return None
        hosts = headers.get_all("Host")
        host_header = hosts[0] if len(hosts) == 1 else ", ".join(hosts)
        host = _split_host(host_header) if len(hosts) == 1 else None
        if host is None or not self.host_ok(host[0]):
            return f"unknown Host {host_header!r}"
        if "websocket" not in (v.lower() for v in headers.get_all("Upgrade")):
            return None
        origins = headers.get_all("Origin")
        if not origins:
            return None  # not a browser; see the module docstring
        origin_header = ", ".join(origins)
        try:
            origin = parse_origin(origin_header)
        except ValueError:
            return f"origin {origin_header!r} is not this lab's page"
        if origin in self.origins:
            return None
        if origin == _origin("http", host[0], host[1]):
            return None  # the page was loaded from the address the websocket connects to
        return f"origin {origin_header!r} is not this lab's page"


def _suggestion(headers: Any) -> str:
    """The ``--allow-origin`` value that would let a refused request through."""
    origins = headers.get_all("Origin")
    hosts = headers.get_all("Host")
    text = origins[0] if len(origins) == 1 else f"http://{hosts[0]}" if len(hosts) == 1 else "ORIGIN"
    # a client's text, shown in a log and a 403: printable ASCII, cut
    return text if re.fullmatch(r"[!-~]{1,200}", text) else "ORIGIN"


def session_token(server: Any, client_id: int) -> str | None:
    """The token in the path of client ``client_id``'s websocket (``/s/<token>``), or None."""
    try:
        connection = server._websock_server._live_connections.get(client_id)
        path = connection.request.path if connection is not None and connection.request is not None else ""
    except AttributeError:
        return None
    match = SESSION_PATH.fullmatch(path.partition("?")[0])
    return match.group(1) if match is not None else None


# -- starting a guarded server ---------------------------------------------------------------------

_SERVE_LOCK = threading.Lock()
_GUARDS: weakref.WeakKeyDictionary[Any, MessageGuard] = weakref.WeakKeyDictionary()


def guard_of(server: Any) -> MessageGuard | None:
    """The message guard of a server made by :func:`start_server` (None for other servers)."""
    try:
        return _GUARDS.get(server)
    except TypeError:
        return None


class _Hook:
    """Wraps ``websockets.asyncio.server.serve`` while one viser server starts."""

    def __init__(self, original: Callable[..., Any], access: Access, guard: MessageGuard, max_bytes: int,
                 addresses: _fair.AddressBook | None) -> None:
        self.original = original
        self.access = access
        self.guard = guard
        self.max_bytes = max_bytes
        self.addresses = addresses
        self.installed = False

    def __call__(self, handler: Any, *args: Any, **kwargs: Any) -> Any:
        if getattr(handler, "__qualname__", "") != _VISER_HANDLER or "process_request" not in kwargs:
            return self.original(handler, *args, **kwargs)
        inner = kwargs["process_request"]
        access, guard, addresses = self.access, self.guard, self.addresses
        refusals = _fair.QuietLog(log, "refused connections")

        def process_request(connection: Any, request: Any) -> Any:
            why = access.refusal(request.headers)
            if why is not None:
                hint = _hint(request.headers)
                refusals(logging.WARNING, why[:200], "ejsrl: refused a connection: %s. %s", why, hint)
                proxied = _proxied(request.headers)  # the proxy's operator reads it: tell what to set
                return connection.respond(http.HTTPStatus.FORBIDDEN, f"This lab refuses the request: {why}.\n"
                                          + (f"{hint}.\n" if proxied else ""))
            upgrade = "websocket" in (v.lower() for v in request.headers.get_all("Upgrade"))
            address = _address(connection)
            if upgrade and addresses is not None and addresses.full(address):
                if addresses.first_refusal(address):
                    log.warning("ejsrl: refused websockets from %s: it has %d open (the most from one address)",
                                address, addresses.limit)
                return connection.respond(http.HTTPStatus.TOO_MANY_REQUESTS,
                                          "Too many connections from your address: close some tabs of this lab.\n")
            session_page = SESSION_PATH.fullmatch(request.path.partition("?")[0])
            if session_page is not None and not upgrade:
                # a tab's own address (/s/<token>/): the lab's page, the same for every tab
                query = request.path.partition("?")[2]
                request.path = "/" + ("?" + query if query else "")
            if upgrade:
                name_browser(request)
            response = inner(connection, request) if inner is not None else None
            if not upgrade and response is not None and request.path.partition("?")[0] in ("/", "/index.html"):
                page_cookie(request, response)
            return response

        def process_response(connection: Any, request: Any, response: Any) -> Any:
            if response is not None and response.status_code == http.HTTPStatus.SWITCHING_PROTOCOLS:
                handshake_cookie(request, response)
            return response

        async def guarded_handler(connection: Any) -> None:
            def check(raw: Any) -> tuple[bytes, dict[str, Any]] | None:
                try:
                    return guard.check(connection, raw)
                except Exception:  # noqa: BLE001 - a bug here must drop the message, not the client
                    guard._log(logging.ERROR, "check raised", "ejsrl: checking a client message failed; it was "
                               "dropped", exc_info=True)
                    return None

            inbox = _fair.Inbox(connection.recv, check, counts=guard.dropped)
            connection.recv = inbox.recv
            address = _address(connection)
            if addresses is not None:
                addresses.opened(address)
            loop = asyncio.get_running_loop()
            deadline = loop.call_later(_fair.REGISTER_SECONDS, _close_unregistered, guard, connection)
            try:
                await handler(connection)
            finally:
                deadline.cancel()
                inbox.close()
                guard.forget(connection)
                if addresses is not None:
                    addresses.closed(address)

        kwargs["process_request"] = process_request
        if kwargs.get("process_response") is None:  # viser 1.1 has none; never replace one it has
            kwargs["process_response"] = process_response
        kwargs["max_size"] = self.max_bytes
        self.installed = True
        return self.original(guarded_handler, *args, **kwargs)


def _address(connection: Any) -> str:
    """The client's IP address of ``connection`` ('' if unknown)."""
    try:
        return str(connection.remote_address[0])
    except (AttributeError, IndexError, TypeError):
        return ""


def _close_unregistered(guard: MessageGuard, connection: Any) -> None:
    """Close ``connection`` if it never registered (see :data:`ejsrl.view._fair.REGISTER_SECONDS`)."""
    if not guard.registered(connection):
        guard._drop("websocket never registered")
        asyncio.ensure_future(connection.close(1008, "no camera message: not a lab page"))


def _proxied(headers: Any) -> bool:
    """True if a proxy says it forwarded the request."""
    return any(headers.get(h) is not None for h in ("X-Forwarded-For", "X-Forwarded-Host", "X-Real-IP", "Forwarded"))


def _hint(headers: Any) -> str:
    """What the teacher should change for a refused request to get through."""
    if _proxied(headers):
        return ("It came through a proxy: the proxy must pass the browser's Host header on "
                "(nginx: proxy_set_header Host $http_host;), and the lab be started with "
                f"--allow-origin {_suggestion(headers)} (see specs/deploy.md)")
    return f"If that page should reach the lab, start the lab with --allow-origin {_suggestion(headers)}"


def start_server(
    host: str = "127.0.0.1",
    port: int = 8080,
    *,
    allow_origins: Iterable[str] = (),
    label: str | None = None,
    verbose: bool = False,
    max_message_bytes: int = MAX_MESSAGE_BYTES,
    answer_as: str | None = None,
    banner: bool = True,
) -> Any:
    """Start a ``viser.ViserServer`` on ``host:port`` (the next free port if taken) behind the
    guards of this module; ``allow_origins``: extra websocket origins (``"*"``: any);
    ``answer_as``: the address whose names the ``Host`` header may carry, when that is not
    ``host`` (a worker behind the front of :mod:`ejsrl.app._front`); ``banner``: let viser
    print its box of addresses.

    Raises ``ValueError`` for a malformed origin and ``RuntimeError`` if this viser's
    internals are not the ones the guards hook (the server is stopped first).
    """
    import viser
    import websockets.asyncio.server as ws_server

    access = Access(host if answer_as is None else answer_as, tuple(allow_origins))
    guard = MessageGuard()
    # behind a front every connection comes from the front: the front counts the addresses
    addresses = _fair.AddressBook() if answer_as is None else None
    with _SERVE_LOCK:
        hook = _Hook(ws_server.serve, access, guard, max_message_bytes, addresses)
        ws_server.serve = hook  # type: ignore[assignment]
        try:
            with contextlib.nullcontext() if banner else contextlib.redirect_stdout(io.StringIO()):
                server = viser.ViserServer(host=host, port=port, label=label, verbose=verbose)
        finally:
            ws_server.serve = hook.original  # type: ignore[assignment]
    problem = None if hook.installed else "viser did not start its websocket server through websockets.asyncio.server.serve"
    if problem is None:
        problem = _missing_internals(server)
    if problem is not None:
        server.stop()
        raise RuntimeError(
            f"ejsrl cannot guard viser {viser.__version__} ({problem}); it was tested with viser "
            f"{', '.join(v + '.x' for v in VISER_TESTED)}: install one with pip install 'viser>=1.1,<1.2'"
        )
    guard.server = server
    _GUARDS[server] = guard
    # the share button asks viser for a public tunnel to the lab; the guard drops that request
    server.gui.configure_theme(show_share_button=False)
    return server


def _missing_internals(server: Any) -> str | None:
    """What this module needs from viser and does not find, or None."""
    from viser import _messages
    from viser.infra import _infra

    consumer = getattr(_infra, "_message_consumer", None)
    if consumer is None or "recv" not in consumer.__code__.co_names:
        return "its message consumer does not read with connection.recv()"
    needs = [
        (server, "_websock_server"),
        (server, "_connected_clients"),
        (server.gui, "_gui_input_handle_from_uuid"),
        (getattr(server, "_websock_server", None), "_live_connections"),
    ]
    for obj, name in needs:
        if not hasattr(obj, name):
            return f"no {type(obj).__name__}.{name}"
    for kind in ("ViewerCameraMessage", "GuiUpdateMessage", *_GIZMO_MESSAGES):
        if not hasattr(_messages, kind):
            return f"no message {kind}"
    return None

