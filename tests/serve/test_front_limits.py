"""The front of a class served from several processes counts each client address (the
processes behind it see only the front's): the cap on websockets from one address holds
through it (issue #30)."""

from __future__ import annotations

import os
import re

import pytest
from websockets.exceptions import InvalidStatus

from testkit.guard_client import Client, run_async
from testkit.served import Served


def test_the_front_caps_websockets_per_address_and_logs_it_once(built, tmp_path, monkeypatch):
    monkeypatch.setenv("EJSRL_MAX_PER_ADDRESS", "3")
    served = Served(built("pendulum"), tmp_path, "--processes", "2", "--max-sessions", "4")
    try:
        async def scenario() -> None:
            mine = [await Client.open(served.port) for _ in range(3)]
            for _ in range(4):
                with pytest.raises(InvalidStatus) as refused:
                    await Client.open(served.port)
                assert refused.value.response.status_code == 429
            other = await Client.open(served.port, source="127.0.0.2")  # another address gets in
            await other.until(lambda: any(re.search(r"s/\d+x", t) for t in other.texts()), "its panel", timeout=60)
            for c in [*mine, other]:
                await c.close()

        run_async(scenario(), timeout=180)
    finally:
        served.stop()
    log = served.err.read_text() + served.out.read_text()
    assert log.count("refused websockets from 127.0.0.1: it has 3 open") == 1, log[-2000:]


def test_a_student_whose_process_was_restarted_is_told_so(built, tmp_path):
    """Issue #30: a student whose copy of the lab was killed (and started again by the front)
    used to get a fresh lab in silence; the page now says the lab was restarted."""
    import signal
    import time

    served = Served(built("pendulum"), tmp_path, "--processes", "2", "--max-sessions", "4", "--grace", "60")
    cookie = "restarted-student-browser"
    try:
        async def first() -> str:
            client = await Client.open(served.port, cookie=cookie)
            await client.until(lambda: any(re.search(r"s/(\d+)x[A-Za-z0-9_-]+/'", t) for t in client.texts()),
                               "the panel", timeout=90)
            token = next(re.search(r"s/(\d+x[A-Za-z0-9_-]+)/'", t).group(1) for t in client.texts()
                         if re.search(r"s/(\d+x[A-Za-z0-9_-]+)/'", t))
            await client.close()
            return token

        token = run_async(first(), timeout=120)
        workers = served.children()
        index = int(token.split("x", 1)[0])
        os.kill(workers[index], signal.SIGKILL)
        deadline = time.monotonic() + 120
        while not (len(served.children()) == 2 and workers[index] not in served.children()
                   and "starting a new one" in served.err.read_text()):
            assert time.monotonic() < deadline, served.err.read_text()
            time.sleep(0.2)
        time.sleep(0.5)

        async def back() -> tuple[str, list[str]]:
            client = await Client.open(served.port, path=f"/s/{token}/", cookie=cookie)
            await client.until(lambda: any("This lab was restarted" in n for n in client.notifications()),
                               "the note that the lab was restarted", timeout=90)
            texts = " ".join(client.texts())
            await client.close()
            return texts, client.notifications()

        texts, notes = run_async(back(), timeout=120)
        assert f"s/{token}/" not in texts  # a new session, at a new address
        assert any("restarted" in n and "This is a new simulation" in n for n in notes)
    finally:
        served.stop()
