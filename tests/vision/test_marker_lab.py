"""The marker-servoing lab, headless: PBVS on the ArUco marker brings the camera to its goal, checked
against the scene's ground truth (the plate's true pose), at the rate the gain sets."""

from __future__ import annotations

import numpy as np

from testkit.labs import headless


def test_the_lab_servoes_to_the_true_goal_at_rate_lambda(built) -> None:
    d = headless(built("marker_servoing"), 5.0, vars="t,found,true_err,est_err,err_t,done", every=3)
    t, true_err = d["t"], d["true_err"]
    assert np.all(d["found"] == 1)
    assert np.nanmax(d["est_err"]) < 4.0  # the marker's position from one image: within 4 mm of the truth
    # the true distance to the goal falls about as exp(-lam t) (lam = 1/s) over the first 2 s
    i0, i2 = np.argmin(np.abs(t - 0.1)), np.argmin(np.abs(t - 2.1))
    ratio = true_err[i2] / true_err[i0]
    assert 0.5 * np.exp(-2.0) < ratio < 2.0 * np.exp(-2.0), ratio
    done = np.flatnonzero(d["done"] == 1)
    assert len(done) and t[done[0]] < 4.5
    assert true_err[done[0]:].max() < 3.0  # and it holds there, truly within 3 mm
