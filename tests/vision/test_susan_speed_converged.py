"""SUSAN tests every pixel with a response at once, so the response it returns and the corners agree.

Testing local maxima round by round (the earlier way, capped at 12 rounds) left maxima of the
returned response untested on textured photographs: peaks of the response map that were
neither a corner nor removed. The timing target lives in bench/vision.py, not here.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from skimage import data

from ejsrl.vision import susan_corners

pytestmark = pytest.mark.usefixtures("susan_path")  # each test on both SUSAN paths (conftest.py)


def _grey(name: str) -> np.ndarray:
    im = getattr(data, name)()
    if im.ndim == 3:
        im = cv2.cvtColor(im, cv2.COLOR_RGB2GRAY)
    return cv2.resize(im, (640, 480), interpolation=cv2.INTER_AREA)


@pytest.mark.parametrize("name", ["camera", "astronaut"])
def test_every_peak_of_the_returned_response_is_a_corner(name):
    img = _grey(name)
    pts, resp = susan_corners(img, subpixel=False, return_response=True)
    assert len(pts) > 100  # a textured photograph
    peaks = (resp > 0) & (resp >= cv2.dilate(resp, np.ones((7, 7), np.uint8)))
    py, px = np.nonzero(peaks)
    corners = pts.astype(int)
    is_corner = np.zeros(resp.shape, bool)
    is_corner[corners[:, 1], corners[:, 0]] = True
    # each peak is a corner, or on a plateau: an equal pixel before it in raster order lies in its
    # window (ties go to the first, as the docstring says)
    rp = np.pad(resp, 3, constant_values=-1)
    lost_tie = np.zeros(len(py), bool)
    for dy in range(-3, 1):
        for dx in range(-3, 4):
            if dy < 0 or dx < 0:
                lost_tie |= rp[py + 3 + dy, px + 3 + dx] == resp[py, px]
    left_out = ~is_corner[py, px] & ~lost_tie
    assert not left_out.any(), f"{left_out.sum()} of {len(py)} peaks of the response are not corners"
    # and each corner is such a peak
    assert peaks[corners[:, 1], corners[:, 0]].all()
