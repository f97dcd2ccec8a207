"""What a student's first visit of a ``--web`` lab downloads (issue #32: at most 30 MB), counted
as Chromium receives it from ``python -m http.server`` (a static host that sends no ``.br``
files: the page fetches the ``.gz`` copies and inflates them itself).

Each lab is opened with an empty cache and every response the page and its worker receive,
bodies and headers, is added up until the panel can be used; the parts are printed (the
figures of specs/web.md). Each lab is built once for this module (``web_lab``).
"""

from __future__ import annotations

import json
import struct
import zipfile

import pytest
from testkit.web_page import visit

#: bytes over the wire of a first visit (issue #32's limit)
FIRST_VISIT_BYTES = 30_000_000
#: the examples whose build is quick enough to test: the issue's three, the six-axis arm example,
#: a lab that uses SciPy (linalg and spatial), one whose 2D panel draws an image (an array) and
#: the heaviest of all (van der Pol: SciPy's integrate, which loads its optimize, 29.2 MB)
LABS = ["pendulum", "paper/six_axis_kinematics", "paper/path_planning_434", "six_axis_arm", "mobile_prm_laser",
        "mobile_dstar_replanning", "van_der_pol"]


@pytest.mark.browser
@pytest.mark.parametrize("name", LABS)
def test_a_first_visit_downloads_at_most_30_mb(page, web_lab, name: str) -> None:
    site, url, _app = web_lab(name)
    # a new student: nothing of this site kept (the page keeps its files in Cache Storage, and an
    # earlier test may have opened it); visit(cold=True) empties the HTTP cache
    cdp = page.context.new_cdp_session(page)
    cdp.send("Storage.clearDataForOrigin", {"origin": url.rstrip("/"), "storageTypes": "all"})
    cdp.detach()
    got: dict[str, int] = {}
    took = visit(page, url, cold=True, timeout_ms=180_000, parts=got).seconds
    assert page.evaluate("ejsWeb.failed") is None
    assert page.evaluate("ejsWeb.call('state')")["error"] is None  # the lab runs (its view too), not only loads
    total = sum(got.values())
    parts = {"python.wasm": "python/python.wasm.gz", "stdlib zip": "python/python315.zip.gz", "lab": "python/lab.bin.gz",
             "viser's client (index.html)": "index.html"}
    rest = total - sum(got.get(p, 0) for p in parts.values())
    print(f"\n{name}: first visit {total / 1e6:.2f} MB over the wire in {took:.1f} s: "
          + ", ".join(f"{k} {got.get(p, 0) / 1e6:.2f}" for k, p in parts.items()) + f", the rest {rest / 1e6:.2f} MB")
    # the count saw every payload whole (the worker's fetches too) ...
    for path in ("python/python.wasm.gz", "python/python315.zip.gz", "python/lab.bin.gz", "index.html"):
        assert got.get(path, 0) >= (site.out / path).stat().st_size, (path, got.get(path))
    # ... and the whole is within the limit
    assert total <= FIRST_VISIT_BYTES, f"{name}: a first visit downloaded {total / 1e6:.2f} MB"


def test_the_zip_keeps_what_the_lab_may_import_and_leaves_the_rest_out(web_lab) -> None:
    """The pendulum's standard library: what CPython 3.15 itself imports (found by running the
    browser's Python: its traceback imports codeop, which the building Python's does not), what
    the lab's modules import only inside functions (a branch the short run did not take), and
    not the one-file modules nothing imports, nor trimesh's optional lxml."""
    site, _url, _app = web_lab("pendulum")
    with zipfile.ZipFile(site.out / "python" / "python315.zip") as z:
        names = set(z.namelist())
    assert {"codeop.pyc", "annotationlib.pyc"} <= names
    assert {"pprint.pyc", "tarfile.pyc", "tomllib/__init__.pyc"} <= names
    left_out = {"imaplib.pyc", "smtplib.pyc", "poplib.pyc", "mailbox.pyc", "lxml/__init__.pyc",
                "charset_normalizer/__init__.pyc", "scipy/__init__.pyc"}
    assert not left_out & names, left_out & names
    # nor the URDF robots' parts (yourdfpy, the UR5's description: a URDF lab's, tests/web/test_web_robotics.py)
    bundle = (site.out / "python" / "lab.bin").read_bytes()
    index = json.loads(bundle[4 : 4 + struct.unpack("<I", bundle[:4])[0]])
    assert not [rel for rel, _size in index if rel.startswith(("yourdfpy/", "ejsrl/robotics/data/"))]
