"""Shared fixtures: paths, building examples, running built apps."""

from __future__ import annotations

from pathlib import Path

import pytest

from testkit import ARTIFACTS, EXAMPLES


def pytest_configure(config: pytest.Config) -> None:
    ARTIFACTS.mkdir(exist_ok=True)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Browser tests share one xdist worker (with ``--dist loadgroup``): one Chromium at a time."""
    for item in items:
        if item.get_closest_marker("browser") is not None:
            item.add_marker(pytest.mark.xdist_group("browser"))


@pytest.fixture(scope="session")
def built(tmp_path_factory: pytest.TempPathFactory):
    """Build an example once per session: ``built("pendulum")`` -> the app folder."""
    from ejsgen.cli import build

    cache: dict[str, Path] = {}

    def _build(name: str) -> Path:
        if name not in cache:
            spec = EXAMPLES / f"{name}.ejs.yaml"
            out = tmp_path_factory.mktemp("apps") / Path(name).name
            cache[name] = build(spec, out)
        return cache[name]

    return _build
