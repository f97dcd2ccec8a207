"""Fixtures for the robotics tests."""

from __future__ import annotations

import json

import pytest

from testkit.robotics import FIXTURES


@pytest.fixture(scope="session")
def puma_ref() -> dict:
    """Puma 560 values from Robotics Toolbox for Python (source stated in the file)."""
    return json.loads((FIXTURES / "puma560_rtb.json").read_text())
