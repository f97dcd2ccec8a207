"""A class across machines behind a real proxy (issue #30): Debian's nginx, configured with
the recipe of ``examples/deploy/nginx.conf`` (only its addresses changed), in front of two
instances of the pendulum lab, all on loopback. New sessions spread over both instances;
a reload and a websocket-only reconnect find their session; the Origin and Host checks hold
through the proxy; an address that reaches the wrong instance is never silently a new lab;
a proxy that does not pass Host on gets a 403 naming the header to set.

nginx runs as root (this test's user) with its config, pid and logs in a temporary folder;
``scripts/setup.sh`` installs it."""

from __future__ import annotations

import http.client
import re
import socket
import subprocess
import time
from pathlib import Path

import pytest
from websockets.exceptions import InvalidStatus

from testkit.classroom import token_of
from testkit.guard_client import Client, run_async
from testkit.served import Served

RECIPE = Path(__file__).resolve().parents[2] / "examples" / "deploy" / "nginx.conf"
NGINX = Path("/usr/sbin/nginx")
BROWSERS = 8


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def configure(recipe: str, instances: list[int], port: int) -> str:
    """The recipe with its two server lines pointing at ``instances``, listening on ``port``,
    plus what the test reads: the instance that answered (a response header), and a location
    of a proxy set up without the Host line."""
    servers = re.findall(r"^\s*server 10\.0\.0\.\d+:8080;\n", recipe, re.M)
    assert len(servers) == 2, "the recipe names two instances"
    out = recipe.replace(servers[0], f"    server 127.0.0.1:{instances[0]};\n")
    out = out.replace(servers[1], f"    server 127.0.0.1:{instances[1]};\n")
    assert "    listen 80;\n" in out
    out = out.replace("    listen 80;\n", f"    listen 127.0.0.1:{port};\n")
    out = out.replace("    location / {\n", "    add_header X-Instance $upstream_addr always;\n\n"
                      "    location /misconfigured/ {\n        proxy_pass http://ejsgen_lab/;\n        proxy_http_version 1.1;\n"
                      "        proxy_set_header X-Forwarded-For $proxy_add_x_forwarded_for;\n    }\n\n"
                      "    location / {\n", 1)
    return out


@pytest.fixture(scope="module")
def proxy(built, tmp_path_factory):
    if not NGINX.exists():
        pytest.fail("Debian's nginx is missing: run scripts/setup.sh")
    tmp = tmp_path_factory.mktemp("nginx")
    instances = [Served(built("pendulum"), tmp_path_factory.mktemp(f"instance{i}"), "--processes", "1",
                        "--max-sessions", "8", "--grace", "30") for i in range(2)]
    port = free_port()
    site = configure(RECIPE.read_text(), [s.port for s in instances], port)
    (tmp / "site.conf").write_text(site)
    for d in ("body", "proxy", "fastcgi", "uwsgi", "scgi"):
        (tmp / d).mkdir()
    (tmp / "nginx.conf").write_text(f"""
user root;
worker_processes 1;
pid {tmp}/nginx.pid;
error_log {tmp}/error.log warn;
events {{ worker_connections 256; }}
http {{
    access_log off;
    client_body_temp_path {tmp}/body;
    proxy_temp_path {tmp}/proxy;
    fastcgi_temp_path {tmp}/fastcgi;
    uwsgi_temp_path {tmp}/uwsgi;
    scgi_temp_path {tmp}/scgi;
    include {tmp}/site.conf;
}}
""")
    nginx = subprocess.Popen([str(NGINX), "-p", str(tmp), "-c", str(tmp / "nginx.conf"), "-g", "daemon off;"],
                             stderr=subprocess.PIPE)
    deadline = time.monotonic() + 20
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), 0.5).close()
            break
        except OSError:
            if nginx.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"nginx did not start: {nginx.stderr.read().decode()}") from None
            time.sleep(0.1)
    yield port, instances
    nginx.terminate()
    nginx.wait(10)
    for s in instances:
        s.stop()


def get(port: int, path: str = "/", cookie: str | None = None, host: str | None = None):
    """``GET path`` through the proxy: (status, headers, body)."""
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    headers = {"Host": host or f"127.0.0.1:{port}"}
    if cookie:
        headers["Cookie"] = f"ejsrl_browser={cookie}"
    conn.request("GET", path, headers=headers)
    r = conn.getresponse()
    out = r.status, r.headers, r.read()
    conn.close()
    return out


async def tab(port: int, cookie: str, path: str = "") -> tuple[Client, str]:
    """A browser's websocket through the proxy: (client, the instance that serves it)."""
    client = await Client.open(port, path=path, cookie=cookie, origin=f"http://127.0.0.1:{port}")
    await client.until(lambda: token_of(client) is not None, "the panel", timeout=90)
    return client, client.ws.response.headers.get("X-Instance", "")


def test_the_recipe_spreads_a_class_and_keeps_each_browser_on_its_instance(proxy):
    port, instances = proxy
    # the page through the proxy names the browser: a cookie the page's scripts cannot read
    status, headers, body = get(port)
    assert status == 200 and b"<html" in body.lower()
    cookie_line = headers["Set-Cookie"]
    assert "HttpOnly" in cookie_line and "SameSite=Strict" in cookie_line and "Path=/" in cookie_line
    cookies = [re.match(r"ejsrl_browser=([A-Za-z0-9_-]+)", get(port)[1]["Set-Cookie"]).group(1)
               for _ in range(BROWSERS)]
    # a browser with its cookie is not given another
    assert get(port, cookie=cookies[0])[1].get("Set-Cookie") is None

    async def scenario() -> dict[str, object]:
        tabs = [await tab(port, c) for c in cookies]
        where = {c: inst for c, (_client, inst) in zip(cookies, tabs)}
        tokens = {c: token_of(client) for c, (client, _i) in zip(cookies, tabs)}
        # a reload: the page at the session's address, then its websocket, from the same instance
        c0 = cookies[0]
        status, headers, _ = get(port, f"/s/{tokens[c0]}/", cookie=c0)
        assert status == 200 and headers["X-Instance"] == where[c0]
        await tabs[0][0].close()
        back, inst = await tab(port, c0, f"/s/{tokens[c0]}")
        assert token_of(back) == tokens[c0] and inst == where[c0]
        # a websocket-only reconnect (the network dropped, the page stayed)
        c1 = cookies[1]
        await tabs[1][0].close()
        again, inst = await tab(port, c1, f"/s/{tokens[c1]}")
        assert token_of(again) == tokens[c1] and inst == where[c1]
        # the Origin check holds through the proxy: another site's page is refused
        try:
            await Client.open(port, cookie=c0, origin="http://evil.example")
            raise AssertionError("another site's page was let through")
        except InvalidStatus as refused:
            assert refused.response.status_code == 403
        # ... and so does the Host check (DNS rebinding: a name the lab was not given)
        assert get(port, host="evil.example")[0] == 403
        for client, _i in [*tabs[2:], (back, ""), (again, "")]:
            await client.close()
        return dict(where=where, tokens=tokens)

    r = run_async(scenario(), timeout=300)
    used = set(r["where"].values())
    assert len(used) == 2, f"every session went to one instance: {r['where']}"


def test_an_address_that_reaches_the_wrong_instance_says_so(proxy):
    port, instances = proxy

    async def scenario() -> list[str]:
        cookie = "wrong-instance-browser-1"
        client, inst = await tab(port, cookie)
        token = token_of(client)
        other = next(s for s in instances if not inst.endswith(f":{s.port}"))
        # the same browser, its address, at the instance that does not hold it (a machine
        # taken out of the proxy, a copied address): a new lab, and a note saying why
        direct = await Client.open(other.port, path=f"/s/{token}", cookie=cookie)
        await direct.until(lambda: token_of(direct) is not None, "the panel", timeout=90)
        assert token_of(direct) != token
        notes = direct.notifications()
        await direct.close()
        await client.close()
        return notes

    notes = run_async(scenario(), timeout=180)
    assert any("another server of the class" in n for n in notes), notes


def test_a_proxy_that_does_not_pass_host_on_is_told_which_header_to_set(proxy):
    port, _instances = proxy
    status, _headers, body = get(port, "/misconfigured/")
    assert status == 403
    text = body.decode()
    assert "proxy_set_header Host $http_host" in text and "specs/deploy.md" in text
