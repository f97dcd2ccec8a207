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
