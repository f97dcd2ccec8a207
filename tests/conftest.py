"""Shared fixtures: paths, building examples, running built apps."""

from __future__ import annotations

from pathlib import Path

import pytest

from testkit import ARTIFACTS, EXAMPLES


def pytest_configure(config: pytest.Config) -> None:
    ARTIFACTS.mkdir(exist_ok=True)
    # xdist registers it; without xdist (-p no:xdist) the mark is still known
    config.addinivalue_line("markers", "xdist_group(name): tests of one group run on one xdist worker")


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Browser tests share one xdist worker (with ``--dist loadgroup``): one Chromium at a time.

    It must run before xdist's own hook, which reads the ``xdist_group`` marks into the test
    ids the scheduler groups by (``tryfirst``): after it, the marks came too late and each
    worker started its own Chromium."""
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


# -- the real browser (Debian's Chromium, no download), one a session for every folder's tests --

CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


@pytest.fixture(scope="session")
def browser_context(tmp_path_factory):
    from playwright.sync_api import sync_playwright

    profile = tmp_path_factory.mktemp("chromium-profile")
    with sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            str(profile),
            executable_path=CHROMIUM,
            headless=True,
            args=ARGS,
            viewport={"width": 1280, "height": 800},
        )
        # waits on the page: limits that hold on a busy machine (testkit.browser.WAIT_SECONDS)
        from testkit.browser import WAIT_SECONDS

        context.set_default_timeout(WAIT_SECONDS * 1000)
        context.set_default_navigation_timeout(WAIT_SECONDS * 1000)
        try:
            yield context
        finally:
            context.close()


@pytest.fixture
def page(browser_context, request):
    page = browser_context.new_page()
    yield page
    ARTIFACTS.mkdir(exist_ok=True)
    try:
        page.screenshot(path=str(ARTIFACTS / f"{request.node.name}.png"))
    finally:
        page.close()
