"""Lab 9, camera calibration (examples/camera_calibration.ejs.yaml), run headless: the board
tours its poses, each view is rendered by the virtual camera, bent by the true lens, its
corners found, and the camera calibrated from the views so far.

The reference is the true camera written out here (the spec's K and distortion), not the
lab's own variables: after 8 views and after all, fx and fy are within 1 %, the principal
point within 2 px, and k1, k2 near the true ones.
"""

from __future__ import annotations

import numpy as np
import pytest
from testkit.labs import headless

LAB = "camera_calibration"
FX, FY, CX, CY = 610.0, 605.0, 326.0, 244.0  # the virtual camera's true intrinsics
K1, K2 = -0.18, 0.05  # and its lens

# another set of 8 poses than the lab's own tour: bx, by, bz (m), roll, pitch, yaw (deg)
OTHER_TOUR = (
    "[[0.02, 0.01, 0.55, 25, 20, 0], [-0.06, 0.04, 0.5, -25, 20, 15], [0.06, -0.04, 0.5, 25, -20, -15],"
    " [0.0, 0.0, 0.48, -15, -30, 40], [0.05, 0.05, 0.6, 30, 0, -20], [-0.05, -0.05, 0.6, -30, 0, 20],"
    " [0.0, 0.03, 0.45, 10, 30, -45], [0.0, -0.03, 0.45, -10, -30, 45]]"
)


def _estimates(d: dict[str, np.ndarray], row: int) -> tuple[float, float, float, float]:
    return tuple(float(d[f"K_est[{i}][{j}]"][row]) for i, j in ((0, 0), (1, 1), (0, 2), (1, 2)))  # type: ignore[return-value]


@pytest.mark.parametrize("tour", ["lab", "other"])
def test_the_tour_recovers_the_true_camera(built, tour):
    sets = {} if tour == "lab" else {"tour": OTHER_TOUR}
    d = headless(built(LAB), 13.0, vars="t,n_views,rms,K_est,dist_est", sets=sets)
    n = d["n_views"]
    views = 12 if tour == "lab" else 8
    assert n[-1] == views, "the board was not found in every view of the tour"
    # no estimate before 3 views
    assert np.all(np.isnan(d["rms"][n < 3]))
    for row in (int(np.flatnonzero(n == 8)[0]), len(n) - 1):
        fx, fy, cx, cy = _estimates(d, row)
        assert abs(fx - FX) / FX < 0.01 and abs(fy - FY) / FY < 0.01, (fx, fy)
        assert np.hypot(cx - CX, cy - CY) < 2.0, (cx, cy)
        assert abs(d["dist_est[0]"][row] - K1) < 0.03 and abs(d["dist_est[1]"][row] - K2) < 0.06
        assert 0.0 < d["rms"][row] < 0.3  # corners are found to a fraction of a pixel
    assert np.all(np.isfinite(d["rms"][n >= 3]))


def test_a_board_outside_the_image_is_not_counted(built):
    """The first tour pose pushed out of the image: that view is refused, the others count."""
    tour = "[[0.4, 0.0, 0.5, 0, 0, 0], [0.0, 0.0, 0.5, 20, 20, 0], [0.0, 0.0, 0.5, -20, -20, 0]]"
    d = headless(built(LAB), 3.0, vars="t,n_views,rms", sets={"tour": tour})
    assert list(d["n_views"]) == [0, 0, 1, 2]
    assert np.all(np.isnan(d["rms"]))


def test_fronto_parallel_views_cannot_fix_the_focal_length(built):
    """What the lab tells students to try: a board seen face-on in every view (no tilt) leaves
    focal length and distance confounded (Zhang's degenerate case): fx is far off, although
    the reprojection error stays small."""
    tour = ("[[0, 0, 0.5, 0, 0, 0], [0.06, 0.04, 0.45, 0, 0, 0], [-0.06, -0.04, 0.55, 0, 0, 0],"
            " [0.05, -0.05, 0.6, 0, 0, 20], [-0.05, 0.05, 0.42, 0, 0, -20]]")
    d = headless(built(LAB), 5.0, vars="t,n_views,rms,K_est", sets={"tour": tour})
    assert d["n_views"][-1] == 5
    fx, fy, _, _ = _estimates(d, -1)
    assert abs(fx - FX) / FX > 0.05 and abs(fy - FY) / FY > 0.05
    assert d["rms"][-1] < 0.3
