"""Fixtures for the mobile-robot tests: the Toolbox's recorded results and their inputs."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

FIXTURES = Path(__file__).resolve().parent / "fixtures"


def _inputs():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("make_mobile_rtb", FIXTURES / "make_mobile_rtb.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)  # type: ignore[union-attr]
    return mod


@pytest.fixture(scope="session")
def rtb_ref() -> dict:
    """Robotics Toolbox 1.5 results (source in the file), recorded by fixtures/make_mobile_rtb.py."""
    return json.loads((FIXTURES / "mobile_rtb.json").read_text())


@pytest.fixture(scope="session")
def inputs():  # type: ignore[no-untyped-def]
    """The recorder module: its controls, maps, queries and covariances."""
    return _inputs()
