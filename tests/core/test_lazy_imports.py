"""``ejsrl`` imports only what can run (issue #32).

A browser's WebAssembly Python (``ejsgen build --web``) has NumPy and SciPy but no OpenCV, no
viser server (msgspec, sockets, threads), no pydantic and no numba. Each test runs a child
Python in which an import hook makes those packages absent (``import cv2`` raises
``ModuleNotFoundError``, as it would there), and checks what a user of the built lab would
notice: the pendulum, six-axis and path-planning labs import and run headless to the very same
CSV as a normal run; every ``ejsrl`` module a lab's model and view declarations need imports;
the vision names that need OpenCV fail with OpenCV's error, the rest (the camera model, visual
servoing) work. Natively, a built lab's start no longer loads OpenCV, viser, asyncio or
importlib.metadata.
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

#: what a browser's Python lacks (the issue's list, and numba: also a C extension it lacks)
ABSENT = ("cv2", "viser", "msgspec", "pydantic", "numba")

HOOK = f"""
import importlib.abc, importlib.util, sys

class _Absent(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in {ABSENT!r}:
            raise ModuleNotFoundError(f"No module named {{name!r}} (absent in this test)", name=name)
        return None

sys.meta_path.insert(0, _Absent())
_find_spec = importlib.util.find_spec
# and asked first (``importlib.util.find_spec(name) is None``: how optional packages are looked for)
importlib.util.find_spec = lambda name, package=None: (
    None if name.partition(".")[0] in {ABSENT!r} else _find_spec(name, package))
"""

#: a built app run as ``python app.py ARGS`` in the child (its own ``ejsrl`` copy, beside it)
RUN_APP = """
import json, runpy
sys.argv = ["app.py", *ARGS]
try:
    runpy.run_path("app.py", run_name="__main__")
    code = 0
except SystemExit as stop:
    code = stop.code
print(json.dumps({"exit": code, "ejsrl": sorted(m for m in sys.modules if m.startswith("ejsrl")),
                  "absent_loaded": sorted(m for m in sys.modules if m.partition(".")[0] in ABSENT)}))
"""

#: every ``ejsrl`` module of the app's copy, imported one by one: name -> "ok" or the error
ENUMERATE = """
import importlib, json, pathlib
root = pathlib.Path("ejsrl")
names = []
for path in sorted(root.rglob("*.py")):
    parts = list(path.with_suffix("").parts)
    if parts[-1] == "__main__":
        continue
    if parts[-1] == "__init__":
        parts.pop()
    names.append(".".join(parts))
out = {}
for name in names:
    try:
        importlib.import_module(name)
        out[name] = "ok"
    except ImportError as exc:
        out[name] = f"{type(exc).__name__}: {exc.name}"
print(json.dumps(out))
"""

#: the view's declarations, which every lab's VIEW is made of; the view's other modules drive
#: viser's server and may need viser (``_wire``, ``_gui``, ``_plots``, ``viser_view``, ...)
VIEW_DECLARATIONS = {"ejsrl.view", "ejsrl.view.elements", "ejsrl.view.elements2d", "ejsrl.view.elements_text"}
#: view modules that drive viser's server, as the issue found them: they need viser
VISER_SERVER = {f"ejsrl.view.{m}" for m in ("_wire", "_console", "_gui", "_lines", "_plots", "_scene_mirror", "_table",
                                             "viser_view")}
#: ejsrl.vision modules written in NumPy alone: they import, and work, without OpenCV
VISION_NUMPY = {"ejsrl.vision", *(f"ejsrl.vision.{m}" for m in ("camera", "servo", "colorspace", "pointcloud", "warm"))}
#: numba kernels, used only where numba is installed
NUMBA_KERNELS = {"ejsrl.vision._susan_numba", "ejsrl.robotics._ik_numba"}
#: the web page's own modules: tested in the browser by tests/web
WEB = "ejsrl.web"

LABS = {  # lab -> headless duration (its independent variable's units)
    "pendulum": "10",
    "paper/six_axis_kinematics": "3",
    "paper/path_planning_434": "3",
}


def _child(app: Path, code: str, *args: str, hooked: bool = True) -> subprocess.CompletedProcess[str]:
    prelude = (HOOK if hooked else f"import sys\nABSENT = {ABSENT!r}\n") + f"ABSENT = {ABSENT!r}\nARGS = {list(args)!r}\n"
    return subprocess.run([sys.executable, "-c", prelude + code], cwd=app, capture_output=True, text=True, timeout=600)


def _csv(path: Path) -> tuple[list[str], np.ndarray]:
    text = path.read_text()
    header = text.splitlines()[0].split(",")
    return header, np.loadtxt(io.StringIO(text), delimiter=",", skiprows=1, ndmin=2)


@pytest.mark.parametrize("lab", LABS)
def test_a_built_lab_runs_without_opencv_viser_msgspec_pydantic_to_the_same_csv(built, lab: str, tmp_path: Path) -> None:
    app = built(lab)
    duration = LABS[lab]
    runs = {}
    for hooked in (False, True):
        csv = tmp_path / f"{'absent' if hooked else 'native'}.csv"
        r = _child(app, RUN_APP, "--headless", "--duration", duration, "--csv", str(csv), hooked=hooked)
        assert r.returncode == 0, r.stderr
        report = json.loads(r.stdout.strip().splitlines()[-1])
        assert report["exit"] in (0, None), r.stderr
        runs[hooked] = (_csv(csv), report)
    (header, native), _ = runs[False]
    (header_absent, absent), report = runs[True]
    assert header_absent == header and len(header) > 1
    assert absent.shape == native.shape and native.shape[0] > 100  # every step's row
    np.testing.assert_allclose(absent, native, rtol=0, atol=1e-12)
    assert native[-1, header.index("t")] > 1.0
    assert report["absent_loaded"] == []
    # what the lab ran: the runtime, the model's solvers and the view's declarations
    assert {"ejsrl.app", "ejsrl.sim.model", "ejsrl.view.elements"} <= set(report["ejsrl"])


def test_the_hook_makes_the_packages_absent(built) -> None:
    """The child really lacks them: otherwise the test above proves nothing."""
    code = "out = {}\nfor name in ABSENT:\n    try:\n        __import__(name)\n        out[name] = 'imported'\n" \
           "    except ModuleNotFoundError:\n        out[name] = 'absent'\nimport json\nprint(json.dumps(out))\n"
    r = _child(built("pendulum"), code)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == {name: "absent" for name in ABSENT}


def test_every_module_a_lab_needs_imports_and_only_opencv_and_viser_users_fail(built) -> None:
    r = _child(built("pendulum"), ENUMERATE)
    assert r.returncode == 0, r.stderr
    result: dict[str, str] = json.loads(r.stdout)
    assert len(result) > 100, sorted(result)
    failed = {name: why for name, why in result.items() if why != "ok" and not name.startswith(WEB)}
    # must import: all of sim, app, world, robotics, mobile, fmi, plant, the view's declarations,
    # and vision's NumPy modules
    must = {name for name in result if not name.startswith(("ejsrl.vision", "ejsrl.view", WEB)) and name not in NUMBA_KERNELS}
    must |= VISION_NUMPY | VIEW_DECLARATIONS
    assert not must & set(failed), {name: failed[name] for name in must & set(failed)}
    assert {"ejsrl", "ejsrl.app", "ejsrl.app.cli", "ejsrl.app.headless", "ejsrl.sim", "ejsrl.view.elements",
            "ejsrl.world", "ejsrl.world.rendering", "ejsrl.world.binding", "ejsrl.robotics", "ejsrl.mobile"} <= must
    # may fail, and only for the package they are built on
    for name, why in failed.items():
        if name.startswith("ejsrl.view."):
            assert why == "ModuleNotFoundError: viser", (name, why)
        elif name in NUMBA_KERNELS:
            assert why == "ModuleNotFoundError: numba", (name, why)
        else:
            assert name.startswith("ejsrl.vision."), (name, why)
            assert why == "ModuleNotFoundError: cv2", (name, why)
    # the OpenCV functions and viser's server side do need them: the hook is felt
    assert {"ejsrl.vision.filters", "ejsrl.vision.features", "ejsrl.vision.markers"} | VISER_SERVER <= set(failed)


def test_vision_names_import_on_first_use(built) -> None:
    """``from ejsrl.vision import CameraModel`` works without OpenCV and gives the camera's projection;
    ``from ejsrl.vision import canny`` fails with OpenCV's own error."""
    code = """
import json
import numpy as np
from ejsrl.vision import CameraModel, interaction_matrix
cam = CameraModel(width=640, height=480, K=np.array([[500.0, 0, 320], [0, 500.0, 240], [0, 0, 1]]))
uv = cam.project_camera(np.array([[0.1, -0.2, 2.0]]))
L = interaction_matrix(np.array([[0.1, 0.2]]), 2.0)
try:
    from ejsrl.vision import canny
    error = None
except ModuleNotFoundError as exc:
    error = exc.name
print(json.dumps({"uv": np.asarray(uv).ravel().tolist(), "L": np.asarray(L).tolist(), "canny": error}))
"""
    r = _child(built("pendulum"), code)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["uv"] == pytest.approx([320 + 500 * 0.1 / 2.0, 240 - 500 * 0.2 / 2.0])
    x, y, Z = 0.1, 0.2, 2.0  # the point-feature interaction matrix, as Chaumette & Hutchinson write it
    want = [[-1 / Z, 0, x / Z, x * y, -(1 + x * x), y], [0, -1 / Z, y / Z, 1 + y * y, -x * y, -x]]
    np.testing.assert_allclose(out["L"], want, rtol=1e-12)
    assert out["canny"] == "cv2"


@pytest.mark.parametrize("lab", ["pendulum", "paper/six_axis_kinematics"])
def test_a_lab_starts_without_loading_opencv_viser_asyncio_or_package_metadata(built, lab: str) -> None:
    """Natively (every package installed): importing a built lab loads none of them."""
    code = "import json\nimport app\nprint(json.dumps(sorted(m for m in ('cv2', 'viser', 'msgspec', 'pydantic', 'asyncio'," \
           " 'importlib.metadata', 'trimesh') if m in sys.modules)))\n"
    r = _child(built(lab), code, hooked=False)
    assert r.returncode == 0, r.stderr
    assert json.loads(r.stdout) == []
