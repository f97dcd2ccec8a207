"""An ``init:`` that never ends is named with its spec line after a few seconds.

Before, an endless ``init:`` left ``--headless`` and a served app silent (a served lab's
front waited 180 s for its processes) with no word of where. Now, headless, served from
one process, or served by a front with several processes, the terminal says within
seconds: ``slow.ejs.yaml:11:5: warning: init: has been running for 3 s ...``; Ctrl+C then
stops it with the usual one line and no traceback.
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from testkit.hostile import ENDLESS_INIT

SPEC = ENDLESS_INIT


@pytest.fixture(scope="module")
def slow_app(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ejsgen.cli import build

    spec = tmp_path_factory.mktemp("slow") / "slow.ejs.yaml"
    spec.write_text(SPEC, encoding="utf-8")
    return build(spec, spec.parent / "app")


def _wait_for(proc: subprocess.Popen[bytes], words: str, seconds: float) -> str:
    """Standard error read until ``words`` appear (or ``seconds`` pass)."""
    assert proc.stderr is not None
    seen = b""
    deadline = time.monotonic() + seconds
    while words.encode() not in seen and time.monotonic() < deadline:
        if select.select([proc.stderr], [], [], 0.5)[0]:
            chunk = os.read(proc.stderr.fileno(), 65536)
            if not chunk:
                break
            seen += chunk
    return seen.decode(errors="replace")


@pytest.mark.parametrize(
    "args",
    [("--headless", "--duration", "1"), ("--port", "0", "--processes", "1"), ("--port", "0", "--processes", "2")],
    ids=["headless", "served", "front"],
)
def test_an_endless_init_is_named_with_its_spec_line_then_stops_on_ctrl_c(slow_app: Path, args: tuple[str, ...]) -> None:
    env = dict(os.environ, EJSRL_SLOW_SECONDS="2")
    proc = subprocess.Popen([sys.executable, str(slow_app / "app.py"), *args], stderr=subprocess.PIPE,
                            stdout=subprocess.DEVNULL, env=env)
    try:
        t0 = time.monotonic()
        text = _wait_for(proc, "Ctrl+C stops it", 60)
        waited = time.monotonic() - t0
        assert "warning: init: has been running for 2 s and is at this line now" in text, text
        line = next(x for x in text.splitlines() if "warning: init:" in x)
        spec_line = int(line.split(":")[1])
        assert SPEC.splitlines()[spec_line - 1].strip() in ("while x > 0:", "n = n + 1"), line
        assert line.split(":")[0].endswith("slow.ejs.yaml")
        assert waited < 30, waited
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode in (130, -signal.SIGINT), err
        assert b"Traceback" not in err, err.decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def _read_until(stream: Any, words: str, seconds: float) -> str:
    """A pipe read until ``words`` appear (or ``seconds`` pass)."""
    seen = b""
    deadline = time.monotonic() + seconds
    while words.encode() not in seen and time.monotonic() < deadline:
        if select.select([stream], [], [], 0.5)[0]:
            chunk = os.read(stream.fileno(), 65536)
            if not chunk:
                break
            seen += chunk
    return seen.decode(errors="replace")


@pytest.mark.parametrize("args", [("--processes", "1"), ("--processes", "2"), ("--shared",)],
                         ids=["served", "front", "shared"])
def test_a_served_lab_whose_init_never_ends_still_opens_its_page(slow_app: Path, args: tuple[str, ...]) -> None:
    """The server starts anyway once ``init:`` overran its wait (it used to keep its port closed
    for good): the page is served, and the terminal says where ``init:`` was stopped."""
    import re
    import urllib.request

    env = dict(os.environ, EJSRL_SLOW_SECONDS="60", EJSRL_INIT_WAIT="3", EJSRL_SHARED_INIT_WAIT="3")
    proc = subprocess.Popen([sys.executable, str(slow_app / "app.py"), "--port", "0", *args], stderr=subprocess.PIPE,
                            stdout=subprocess.PIPE, env=env)
    try:
        assert proc.stdout is not None and proc.stderr is not None
        out = _read_until(proc.stdout, "(Ctrl+C to stop)", 90)
        found = re.search(r"serving on (http://127\.0\.0\.1:\d+)", out)
        assert found, out + _read_until(proc.stderr, "\n\n", 1)
        with urllib.request.urlopen(found.group(1) + "/", timeout=30) as reply:
            assert reply.status == 200
            assert b"<html" in reply.read().lower()
        err = _read_until(proc.stderr, "was stopped", 30)
        line = next(x for x in err.splitlines() if "did not end within 3 s" in x)
        assert line.split(":")[0].endswith("slow.ejs.yaml"), line
        assert SPEC.splitlines()[int(line.split(":")[1]) - 1].strip() in ("while x > 0:", "n = n + 1"), line
        assert ("Reset runs init: again" in line) == ("--shared" in args), line
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
