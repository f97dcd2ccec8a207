"""Helpers for the paper labs' tests: run a built lab headless, read its CSV, and small
independent references (standard DH written out here, a pinhole camera, finite
differences) that do not go through the runtime's own kinematics or dynamics code."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from testkit import run_app

#: the labs, as names for the session's ``built`` fixture (examples/<name>.ejs.yaml)
LABS = {
    "kinematics": "paper/six_axis_kinematics",
    "path": "paper/path_planning_434",
    "dynamics": "paper/inverse_dynamics_payload",
    "servo": "paper/visual_servoing_eih",
    "pid": "paper/pid_dc_motor_control",
    "multi": "paper/multi_robot_eih",
}


def headless(app: Path, duration: float, *, vars: str | None = None, every: int = 1, sets: dict[str, str] | None = None) -> dict[str, np.ndarray]:
    """Run ``app.py --headless`` for ``duration`` simulated seconds; the CSV as columns."""
    args = ["--headless", "--duration", str(duration), "--csv", "-", "--every", str(every)]
    if vars:
        args += ["--vars", vars]
    for name, value in (sets or {}).items():
        args += ["--set", f"{name}={value}"]
    r = run_app(app, *args, timeout=120)
    assert r.returncode == 0, r.stderr
    data = np.genfromtxt(io.StringIO(r.stdout), delimiter=",", names=True, deletechars="")
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def vector(d: dict[str, np.ndarray], name: str, n: int) -> np.ndarray:
    """Columns ``name[0] .. name[n-1]`` stacked as (rows, n)."""
    return np.column_stack([d[f"{name}[{j}]"] for j in range(n)])


def matrices(d: dict[str, np.ndarray], name: str) -> np.ndarray:
    """A 4x4 matrix variable's 16 columns ``name[i][j]`` as (rows, 4, 4)."""
    return np.stack([np.column_stack([d[f"{name}[{i}][{j}]"] for j in range(4)]) for i in range(4)], axis=1)


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """One standard Denavit-Hartenberg link transform Rz(theta) Tz(d) Tx(a) Rx(alpha), written out."""
    ct, st, ca, sa = np.cos(theta), np.sin(theta), np.cos(alpha), np.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d], [0.0, 0.0, 0.0, 1.0]])


def dh_frames(q: np.ndarray, table: list[tuple[float, float, float, float]], base: np.ndarray | None = None) -> list[np.ndarray]:
    """Frames 0..n of a standard-DH arm with rows ``(d, a, alpha, offset)``: [base, base A1, ...]."""
    T = np.eye(4) if base is None else np.asarray(base, float)
    out = [T]
    for qj, (d, a, alpha, offset) in zip(q, table):
        T = T @ dh(qj + offset, d, a, alpha)
        out.append(T)
    return out


def pinhole(points_world: np.ndarray, T_world_camera: np.ndarray, width: int, height: int, fov_deg: float) -> np.ndarray:
    """Project world points (N, 3) to pixels (x, y) with a centred pinhole of vertical field of view ``fov_deg``."""
    f = 0.5 * height / np.tan(np.radians(fov_deg) / 2)
    R, t = T_world_camera[:3, :3], T_world_camera[:3, 3]
    P = (points_world - t) @ R  # camera frame
    return np.column_stack([f * P[:, 0] / P[:, 2] + (width - 1) / 2, f * P[:, 1] / P[:, 2] + (height - 1) / 2])


def settle_time(t: np.ndarray, x: np.ndarray, target: float, band: float = 0.02) -> float:
    """The first time after which ``x`` stays within ``band`` (relative) of ``target``."""
    outside = np.flatnonzero(np.abs(x - target) > band * abs(target))
    if len(outside) == 0:
        return float(t[0])
    if outside[-1] == len(t) - 1:
        return float("inf")
    return float(t[outside[-1] + 1])
