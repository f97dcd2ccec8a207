"""The eye-in-hand visual-servoing lab (paper figures 11-12) run headless, with the virtual
camera, SUSAN and IBVS (or PBVS on the PnP pose) in the loop: from the default start and from
two others, the four corners converge to the desired square to under a pixel; a start that
loses corners says so in the UI's messages (printed as alerts in a headless run).

Independent check of where the arm ended: the square's true corners projected from the
final camera pose (standard DH written out in the test, the lab's camera mounting, a
pinhole with the camera's field of view) land on the desired square.
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from testkit import run_app
from testkit.labs import LABS, dh_frames, headless, pinhole, vector

# Puma 560 standard DH (d, a, alpha, offset), as published (Corke & Armstrong-Helouvry)
PUMA = [(0.67183, 0.0, np.pi / 2, 0), (0.0, 0.4318, 0.0, 0), (0.15005, 0.0203, -np.pi / 2, 0),
        (0.4318, 0.0, np.pi / 2, 0), (0.0, 0.0, -np.pi / 2, 0), (0.0, 0.0, 0.0, 0)]
T_TOOL_CAM = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.05], [0, 0, 0, 1.0]])
# the dark square: 0.16 m across, centred at (0.55, 0.15), its top face at z = 0.204
SQUARE = np.array([[0.47, 0.07, 0.204], [0.63, 0.07, 0.204], [0.63, 0.23, 0.204], [0.47, 0.23, 0.204]])
S_STAR = np.array([[109.5, 69.5], [209.5, 69.5], [209.5, 169.5], [109.5, 169.5]])  # a centred 100 px square

STARTS = {
    "default": None,
    "rolled": "[26, 52, -192, -6, -36, -160]",
    "shifted": "[30, 42, -180, 10, -50, -150]",
}


@pytest.mark.parametrize("mode", ["IBVS", "PBVS"])
@pytest.mark.parametrize("start", list(STARTS))
def test_the_corners_converge_to_the_desired_square(built, start, mode):
    sets = {"mode": mode} if STARTS[start] is None else {"q_start_deg": STARTS[start], "mode": mode}
    d = headless(built(LABS["servo"]), 5.5, vars="t,err_px,v_norm,found,done,q,s_star", sets=sets)
    t, err, vnorm = d["t"], d["err_px"], d["v_norm"]
    assert np.all(d["found"] == 4), "a corner was lost"
    s_star = np.array([[d[f"s_star[{i}][{j}]"][0] for j in range(2)] for i in range(4)])
    np.testing.assert_allclose(s_star, S_STAR)
    assert err[0] > 30  # it starts far from the goal
    assert err[-1] < 1.0
    assert np.all(err[t > t[-1] - 0.4] < 1.0)  # and stays there
    assert err[np.searchsorted(t, 2.0)] < 0.45 * err[0]  # roughly exponential at rate lambda = 1/s
    # done: every corner within the 0.5 px tolerance, and the arm holds still
    assert d["done"][-1] == 1 and err[-1] < 0.5 and vnorm[-1] == 0.0
    assert np.all(np.diff(d["done"]) >= 0)  # once there it stays there
    # where the camera really is: the true corners seen from there sit on the desired square
    q = vector(d, "q", 6)[-1]
    T_cam = dh_frames(q, PUMA)[-1] @ T_TOOL_CAM
    seen = pinhole(SQUARE, T_cam, 320, 240, 50.0)
    order = [int(np.argmin(np.linalg.norm(S_STAR - p, axis=1))) for p in seen]
    assert sorted(order) == [0, 1, 2, 3]
    assert np.abs(seen - S_STAR[order]).max() < 2.0


def _alerts(app, *sets: str) -> list[str]:
    args = ["--headless", "--duration", "1.0", "--csv", "-", "--every", "30"]
    for kv in sets:
        args += ["--set", kv]
    r = run_app(app, *args, timeout=120)
    assert r.returncode == 0, r.stderr
    return [line for line in r.stderr.splitlines() if line.startswith("alert:")]


def test_corners_leaving_the_image_are_reported_once_and_a_good_start_is_quiet(built):
    app = built(LABS["servo"])
    assert _alerts(app) == []
    off = _alerts(app, "q_start_deg=[45, 45, -182, 8, -48, -135]")  # the square half out of view
    assert len(off) == 1 and "leaving the image: 2 of 4" in off[0], off


def test_a_served_class_has_susans_compiled_kernels_before_the_first_student(built, tmp_path):
    """Serving a class measures a few frames of the lab; when they start compiling SUSAN's
    numba kernels, the compile is finished before the class is let in (a compile in a busy
    server crawls, and meanwhile every session runs the slower NumPy path)."""
    app_dir = built("paper/visual_servoing_eih")
    script = (
        "import sys\n"
        "from ejsrl.app import load_app\n"
        "from ejsrl.vision import _susan\n"
        f"app = load_app({str(app_dir)!r})\n"
        "server = app.serve('127.0.0.1', 0, block=False, per_client=True)\n"
        "print('ready:', _susan._COMPILED.thread is not None, _susan._COMPILED.module is not None)\n"
        "app.stop(); server.stop()\n"
    )
    # an empty numba cache: the compile takes seconds, as on a machine's first served lab
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "numba-cache"))
    r = subprocess.run([sys.executable, "-P", "-c", script], capture_output=True, text=True, timeout=300, cwd=tmp_path, env=env)
    assert r.returncode == 0, r.stderr
    assert "ready: True True" in r.stdout, r.stdout + r.stderr
