"""Web builds of the examples, served by ``python -m http.server`` as a teacher would try them."""

from __future__ import annotations

import contextlib
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import pytest

from testkit import EXAMPLES


@contextlib.contextmanager
def static_server(folder: Path) -> Iterator[str]:
    """``python -m http.server`` on a free port of 127.0.0.1 serving ``folder``; its URL."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    proc = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1", "-d", str(folder)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}/"
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                with urllib.request.urlopen(url + "python/manifest.json", timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise
                time.sleep(0.1)
        yield url
    finally:
        proc.terminate()
        proc.wait(timeout=10)


@pytest.fixture(scope="module")
def web_lab(tmp_path_factory: pytest.TempPathFactory) -> Iterator:
    """``web_lab(name)`` -> ``(site, url, app_dir)``: the example built with ``--web`` (once per
    module: a module's visits and rewrites of a site stay its own, on a port of its own, so no
    other module finds it in the browser's caches), served, and its normal build (for native
    runs); ``name`` may also be a spec's path."""
    from ejsgen._web_build import build_web
    from ejsgen.cli import build

    made: dict[str | Path, tuple] = {}
    with contextlib.ExitStack() as stack:

        def make(name: str | Path) -> tuple:
            if name not in made:
                spec = name if isinstance(name, Path) else EXAMPLES / f"{name}.ejs.yaml"
                base = tmp_path_factory.mktemp("web")
                site = build_web(spec, base / "site")
                app_dir = build(spec, base / "app")
                made[name] = (site, stack.enter_context(static_server(site.out)), app_dir)
            return made[name]

        yield make


@pytest.fixture
def until():
    """``until(page, js, arg=None, timeout=30.0)``: evaluate ``js`` (a function of ``arg`` that may
    return a promise, e.g. ``ejsWeb.call('state')...``) until it gives a truthy value; that value.
    Not ``page.wait_for_function``: it takes a returned promise as truthy at once."""

    def wait(page, js: str, arg=None, timeout: float = 30.0):
        deadline = time.monotonic() + timeout
        while True:
            value = page.evaluate(js, arg)
            if value:
                return value
            if time.monotonic() > deadline:
                raise AssertionError(f"still false after {timeout} s: {js}")
            page.wait_for_timeout(50)  # the page's next frames

    return wait
