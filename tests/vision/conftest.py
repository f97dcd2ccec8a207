"""Shared scenes and helpers for the vision and rendering tests."""

from __future__ import annotations

import numpy as np
import pytest

from ejsrl.vision import look_at  # noqa: F401 - the tests import it from here
from ejsrl.world import World
from ejsrl.world.scene import MeshNode, Part

SQUARE_HALF = 0.1  # the target square is 0.2 m across


def square_corners_local(half: float = SQUARE_HALF) -> np.ndarray:
    return np.array([[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]])


def square_world(T_world_square: np.ndarray, half: float = SQUARE_HALF, backing: bool = True) -> World:
    """A white flat square (two triangles, both sides) on a larger dark plate just behind it."""
    w = World()
    V = square_corners_local(half)
    F = [[0, 1, 2], [0, 2, 3], [0, 2, 1], [0, 3, 2]]  # both windings: visible from either side
    w.add(MeshNode("square", mesh_parts=(Part(V, F, (1.0, 1.0, 1.0)),), T_parent_local=T_world_square))
    if backing:
        B = square_corners_local(4 * half)
        B[:, 2] = -0.002
        w.add(MeshNode("plate", mesh_parts=(Part(B, F, (0.1, 0.1, 0.12)),), T_parent_local=T_world_square))
    return w


def corners_world(T_world_square: np.ndarray, half: float = SQUARE_HALF) -> np.ndarray:
    V = square_corners_local(half)
    return V @ T_world_square[:3, :3].T + T_world_square[:3, 3]


@pytest.fixture(params=["numpy", "numba"])
def susan_path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> str:
    """Run a test once with each SUSAN implementation: the NumPy/OpenCV path and numba's compiled
    kernels (the ``[fast]`` extra, in the test extra too, so both run here and in CI)."""
    from ejsrl.vision import _susan

    monkeypatch.setattr(_susan, "BACKEND", request.param)
    assert _susan.susan_backend() == request.param
    return request.param


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)
