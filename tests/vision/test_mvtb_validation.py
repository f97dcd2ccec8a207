"""The MVTB-core functions given bad images (empty, 1-D, NaN, wrong channels, wrong dtype):
each raises ValueError with a message, or returns a result; none kills the interpreter
(run in a child process, so a crash is reported rather than taking the test run down)."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

CALLS = {
    "find_chessboard": "V.find_chessboard(b, (8, 5))",
    "optical_flow": "V.optical_flow(b, b)",
    "disparity": "V.disparity(b, b)",
    "detect_features": "V.detect_features(b)",
    "distance_transform": "V.distance_transform(b)",
    "watershed": "V.watershed(b, np.zeros(np.shape(b)[:2], np.int32))",
    "split_touching": "V.split_touching(b)",
    "skeleton": "V.skeleton(b)",
    "gaussian_pyramid": "V.gaussian_pyramid(b)",
    "laplacian_pyramid": "V.laplacian_pyramid(b)",
    "log_filter": "V.log_filter(b)",
    "dog_filter": "V.dog_filter(b)",
    "hu_moments": "V.hu_moments(b)",
    "rgb_to_lab": "V.rgb_to_lab(b)",
    "undistort": "V.CameraModel(4, 3, distortion=[0.1, 0, 0, 0, 0]).undistort(b)",
}
BAD = {
    "empty 0x0": "np.zeros((0, 0), np.uint8)",
    "empty 0x5x3": "np.zeros((0, 5, 3), np.uint8)",
    "1-D": "np.zeros(7, np.uint8)",
    "nan float": "np.full((8, 8), np.nan)",
    "4-D": "np.zeros((2, 2, 2, 2), np.uint8)",
    "strings": "np.array([['a', 'b'], ['c', 'd']])",
}

CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import ejsrl.vision as V
    call = sys.argv[1]
    for case, expr in json.loads(sys.argv[2]).items():
        b = eval(expr)
        try:
            eval(call)
            out = "ok"
        except ValueError as exc:
            out = "ValueError: " + str(exc)
        except Exception as exc:
            out = type(exc).__name__ + ": " + str(exc)
        print(json.dumps([case, out]), flush=True)
    """
)


def test_bad_images_raise_valueerror_and_never_crash():
    problems = []
    # one child per function, every bad input in turn, so a crash names its function and input
    for name, call in CALLS.items():
        r = subprocess.run([sys.executable, "-c", CHILD, call, json.dumps(BAD)], capture_output=True, text=True, timeout=120)
        done = dict(json.loads(line) for line in r.stdout.splitlines() if line.startswith("["))
        if r.returncode != 0:
            crashed = next(case for case in BAD if case not in done)
            problems.append(f"{name}({crashed}): the interpreter died ({r.returncode}): {r.stderr[-300:]}")
        for case, out in done.items():
            if out != "ok" and not out.startswith("ValueError: "):
                problems.append(f"{name}({case}): {out}")
            elif out.startswith("ValueError: ") and len(out) < 25:
                problems.append(f"{name}({case}): unhelpful message {out!r}")
    assert not problems, "\n".join(problems)
