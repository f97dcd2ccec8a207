"""Real servers for the plant tests, each on a free 127.0.0.1 port and stopped afterwards:
Debian's mosquitto with a temporary config, and the reference plant as its own process."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterator

import pytest

from testkit.plant import MOSQUITTO, Broker, PlantProc, free_port, wait_port  # noqa: F401 - fixtures below, names for tests


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
    from ejsrl.app._plant_link import PlantLink

    links: list[PlantLink] = []

    def make(**kw) -> PlantLink:
        link = PlantLink("127.0.0.1", broker.port, **kw)
        links.append(link)
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30), link.note
        return link

    yield make
    for link in links:
        link.close()
