"""Real servers for the plant tests, each on a free 127.0.0.1 port and stopped afterwards:
Debian's mosquitto with a temporary config, and the reference plant as its own process."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from testkit.plant import MOSQUITTO, Broker, ConnectedLinks, PlantProc, free_port, wait_port  # noqa: F401 - fixtures below, names for tests


@pytest.fixture
def broker(tmp_path: Path) -> Iterator[Broker]:
    if not os.path.exists(MOSQUITTO):
        pytest.fail("mosquitto is missing: run scripts/setup.sh (it installs Debian's mosquitto)")
    b = Broker(tmp_path, free_port())
    b.start()
    yield b
    b.kill()


@pytest.fixture
def plant(broker: Broker, tmp_path: Path) -> Iterator[PlantProc]:
    """The reference plant on ``broker`` with a 0.5 s watchdog and a 4 s slot."""
    p = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--watchdog", "0.5", "--slot", "4"])
    yield p
    p.stop()


@pytest.fixture
def link_factory(broker: Broker) -> Iterator:
    """``make(**kw)``: a connected MQTT ``PlantLink`` to ``broker`` (``session``, ``alive``, ...); closed after."""
    from ejsrl.app._plant_link import PlantLink

    with ConnectedLinks(lambda **kw: PlantLink("127.0.0.1", broker.port, **kw)) as make:
        yield make


@dataclass
class LeaseQueue:
    """A holder that holds the plant and a session ``waiting`` first in its queue; while ``flag``
    is set the holder's ``alive()`` gives the value the queue was made with."""

    flag: threading.Event
    holder: Any
    waiting: Any

    def hand_over(self, timeout: float) -> float:
        """Set ``flag`` and return the seconds until ``waiting`` holds the plant (at most ``timeout``)."""
        self.flag.set()
        t0 = time.monotonic()
        assert self.waiting.wait_for(lambda l: l.holds_lease, timeout)
        return time.monotonic() - t0


@pytest.fixture
def lease_queue() -> Callable[..., LeaseQueue]:
    """``lease_queue(make, alive_when_set)``: a :class:`LeaseQueue` of links made by ``make``
    (``link_factory``, or ``ConnectedLinks``' for OPC UA); ``alive_when_set``: what the holder's
    ``alive()`` says once the flag is set (seconds since its tab was last seen; ``math.inf``: gone)."""

    def queue(make: Callable[..., Any], alive_when_set: float) -> LeaseQueue:
        flag = threading.Event()
        holder = make(session="holder", alive=lambda: alive_when_set if flag.is_set() else 0.0)
        holder.request_lease()
        assert holder.wait_for(lambda l: l.holds_lease, 20)
        waiting = make(session="waiting")
        waiting.request_lease()
        assert waiting.wait_for(lambda l: l.queue_position == 1, 20)
        return LeaseQueue(flag, holder, waiting)

    return queue
