"""Lab 9's About text says how close each estimate gets, and the lab bears it out.

A new user's trial compared k1, k2 with the truth after Capture + the tour (13 views) and
found k2 = +0.09 for +0.05: the weak conditioning of k2 with ~0.06 px corner noise, not a
bug. The About text now says what is well determined; these runs (the Capture pose, then
the tour's 12, then 8 more tilted views near the image's corners) check each number it
gives against the true camera written out here.
"""

from __future__ import annotations

import yaml
from testkit import EXAMPLES
from testkit.labs import headless

LAB = "camera_calibration"
FX, FY, CX, CY, K1, K2 = 610.0, 605.0, 326.0, 244.0, -0.18, 0.05
CAPTURE = "[0, 0, 0.5, 15, -20, 0]"  # the sliders' start pose, where a student first presses Capture
TOUR = ("[0.0, 0.0, 0.50, 0, 0, 0], [-0.08, -0.06, 0.50, 20, -25, 5], [0.08, -0.06, 0.50, 20, 25, -5],"
        " [-0.08, 0.06, 0.50, -20, -25, -5], [0.08, 0.06, 0.50, -20, 25, 5], [0.0, 0.0, 0.42, 30, 0, 10],"
        " [0.0, 0.0, 0.42, -30, 0, -10], [0.0, 0.0, 0.45, 0, 35, 0], [0.0, 0.0, 0.45, 0, -35, 0],"
        " [-0.09, 0.0, 0.55, 10, 15, 30], [0.09, 0.0, 0.55, -10, -15, -30], [0.0, 0.07, 0.60, 25, 10, 0]")
CORNERS = ("[-0.12, -0.09, 0.55, 25, -30, 10], [0.12, -0.09, 0.55, 25, 30, -10], [-0.12, 0.09, 0.55, -25, -30, -10],"
           " [0.12, 0.09, 0.55, -25, 30, 10], [-0.13, 0.0, 0.5, 0, -35, 0], [0.13, 0.0, 0.5, 0, 35, 0],"
           " [0.0, -0.1, 0.5, -35, 0, 0], [0.0, 0.1, 0.5, 35, 0, 0]")


def _about() -> str:
    return " ".join(yaml.safe_load((EXAMPLES / f"{LAB}.ejs.yaml").read_text())["description"].split())


def test_the_about_text_says_how_close_each_estimate_gets():
    about = _about()
    for claim in ("fx and fy come within about 0.1 %", "principal point within about 1 px",
                  "k1 within about 10 %", "k2 only loosely (about +0.09 for +0.05)",
                  "trade off against k1", "With exact corners the same views give k2 = 0.050",
                  "More tilted views with the board near the image's corners help",
                  "eight more bring k2 to about 0.08 and k1 within 5 %"):
        assert claim in about, claim


def test_the_numbers_of_the_about_text_hold(built):
    app = built(LAB)
    d = headless(app, 13.0, vars="t,n_views,K_est,dist_est", sets={"tour": f"[{CAPTURE}, {TOUR}]"})
    assert d["n_views"][-1] == 13
    fx, fy, cx, cy = (float(d[f"K_est[{i}][{j}]"][-1]) for i, j in ((0, 0), (1, 1), (0, 2), (1, 2)))
    k1, k2 = float(d["dist_est[0]"][-1]), float(d["dist_est[1]"][-1])
    assert abs(fx - FX) / FX < 0.001 and abs(fy - FY) / FY < 0.001, (fx, fy)
    assert abs(cx - CX) < 1.5 and abs(cy - CY) < 1.5, (cx, cy)  # "within about 1 px"
    assert 0.05 < abs(k1 - K1) / abs(K1) < 0.1, k1  # -0.19 for -0.18
    assert 0.085 < k2 < 0.095, k2  # "about +0.09"
    more = headless(app, 21.0, vars="t,n_views,dist_est", sets={"tour": f"[{TOUR}, {CORNERS}]"})
    assert more["n_views"][-1] == 20
    k1m, k2m = float(more["dist_est[0]"][-1]), float(more["dist_est[1]"][-1])
    assert abs(k1m - K1) / abs(K1) < 0.05 and 0.07 < k2m < 0.085 and k2m < k2, (k1m, k2m)
