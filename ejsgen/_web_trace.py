"""Which modules a built lab loads: the list a web build trims the standard library zip to.

:func:`traced_modules` runs the lab natively in a child process, as the browser will: the
packages a browser lacks are made unimportable first (:data:`HIDDEN`, so the runtime's
stand-ins of :mod:`ejsrl.web._absent` are what loads), then the page's lab is made
(:class:`ejsrl.web.lab.WebLab`), its client's first camera message handled, a few frames played
and a one-second headless run made. The names in ``sys.modules`` afterwards are the answer. Every top-level package the browser's
Python does not have (neither in its zip nor in the lab) is unimportable in that run.

The browser's Python (3.15, NumPy 2.5, SciPy 1.18) is newer than this one, so the zip keeps
whole packages where a module of them was loaded, and a safety list
(:data:`ejsgen._web_stdlib.ALWAYS`) of what newer CPython modules import on their own.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from ejsgen.errors import EjsError

__all__ = ["traced_modules", "stdlib_imports", "HIDDEN", "TraceError"]

#: packages the browser's Python does not have, hidden from the traced run; and three it has
#: that trimesh only uses when present (graphs, image textures, SVG and XML meshes, which --web
#: refuses): left out of the page to keep its download small (6 MB; lxml's Python 0.15 MB), so
#: trimesh runs without them there, as on a machine without them
HIDDEN = ("msgspec", "websockets", "zstandard", "rich", "cv2", "ssl", "_ssl", "networkx", "PIL", "lxml")

_SCRIPT = r"""
import importlib.abc, importlib.util, json, os, sys
hidden = set(json.loads(os.environ["EJSWEB_HIDDEN"]))
there = set(json.loads(os.environ["EJSWEB_THERE"])) | set(sys.stdlib_module_names)
native = {}
stdlib = os.path.realpath(os.path.dirname(os.__file__))  # not sysconfig: it imports what is asked about
def platform_own(top):
    # a module of this Python's own standard library that the list of its names leaves out
    # (_sysconfigdata__linux_x86_64-linux-gnu: sysconfig's data for this platform); the
    # browser's Python has its own under another name, so it loads here and the zip skips it
    if top not in native:
        origin = None
        for finder in sys.meta_path:
            if isinstance(finder, Hide) or not hasattr(finder, "find_spec"):
                continue
            try:
                spec = finder.find_spec(top, None)
            except (ImportError, ValueError):
                spec = None
            if spec is not None:
                origin = spec.origin
                break
        native[top] = bool(origin) and os.path.realpath(origin).startswith(stdlib + os.sep) and (
            "site-packages" not in origin and "dist-packages" not in origin)
    return native[top]
def absent(name):
    top = name.split(".")[0]
    return top in hidden or (top not in there and not platform_own(top))
_find = importlib.util.find_spec
def find_spec(name, package=None):
    if absent(name):
        return None
    return _find(name, package)
importlib.util.find_spec = find_spec
def optional_scipy(name):
    # trimesh imports SciPy when it can, for a few functions; a lab that does not use SciPy
    # itself gets a trimesh without it in the page (as on a machine without SciPy), which keeps
    # SciPy out of its download and its start
    if name.split(".")[0] != "scipy" or "scipy" in sys.modules:
        return False
    frame = sys._getframe(2)
    while frame is not None and frame.f_code.co_filename.startswith("<frozen"):
        frame = frame.f_back
    return frame is not None and f"{os.sep}trimesh{os.sep}" in frame.f_code.co_filename
class Hide(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if optional_scipy(name):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        if absent(name):
            for finder in sys.meta_path:
                if type(finder).__name__ == "_Absent":
                    spec = finder.find_spec(name)
                    if spec is not None:
                        return spec
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
for name in [m for m in sys.modules if absent(m)]:
    del sys.modules[name]
sys.meta_path.insert(0, Hide())
sys.path.insert(0, os.environ["EJSWEB_LAB"])
io_dir = os.environ["EJSWEB_IO"]
from ejsrl.web import lab as L
L.INBOX, L.OUTBOX = os.path.join(io_dir, "inbox"), os.path.join(io_dir, "outbox")
lab = L.open_lab("app", lab_dir=os.environ["EJSWEB_LAB"])
lab.frame()
from ejsrl.web import _msgpack
camera = {"type": "ViewerCameraMessage", "wxyz": [1.0, 0.0, 0.0, 0.0], "position": [3.0, 3.0, 3.0],
          "image_height": 600, "image_width": 800, "fov": 1.0, "near": 0.01, "far": 1000.0,
          "look_at": [0.0, 0.0, 0.0], "up_direction": [0.0, 0.0, 1.0]}
raw = _msgpack.encode(camera)
with open(L.INBOX, "wb") as f:
    f.write(len(raw).to_bytes(4, "little") + raw)
lab.frame()
lab.app.play()
for _ in range(10):
    lab.frame()
L.headless_csv(lab.module, 0.2, path=os.path.join(io_dir, "run.csv"))
if "scipy" in sys.modules:
    # the browser's SciPy (1.18) clones NumPy's namespace with `from numpy import *`, which loads
    # every subpackage NumPy names in __all__ (f2py, testing, ma, ...): load them here as well
    exec("from numpy import *", {})
    import pydoc  # noqa: F401 - and its docstring scraper imports pydoc
print("\x1e" + json.dumps(sorted(sys.modules)))
"""


class TraceError(EjsError):
    """The lab could not be run natively to find what it imports (printed as is: ``error: ...``)."""


#: seconds the traced run's ``init:`` may go on after it was said to be slow (its spec line
#: printed): an endless ``init:`` ends the build with that line instead of holding it
#: (``EJSGEN_WEB_INIT_GRACE`` overrides)
INIT_GRACE = float(os.environ.get("EJSGEN_WEB_INIT_GRACE", "30"))
_SLOW = "warning: init: has been running"


def traced_modules(lab_dir: Path, io_dir: Path, there: list[str], *, timeout: float = 300.0, shown: tuple[str, ...] = ()) -> list[str]:
    """The names of the modules the lab in ``lab_dir`` (a built app folder with ``app.py``)
    loads when it runs as a web page; ``io_dir``: a scratch folder for its files; ``there``:
    the top-level packages the browser's Python has besides the standard library (the zip's
    and the lab's): any other is made unimportable for the run, as it is in the browser;
    ``shown``: packages of :data:`HIDDEN` this lab needs, left importable (lxml for URDF files).

    An ``init:`` that runs on is said at once, with its spec line (the runtime's slow-block
    warning, echoed), and ends the build :data:`INIT_GRACE` seconds later with a
    :class:`TraceError` at that line; so does a run past ``timeout`` seconds."""
    io_dir.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, EJSWEB_HIDDEN=json.dumps([h for h in HIDDEN if h not in shown]), EJSWEB_THERE=json.dumps(sorted(there)),
               EJSWEB_LAB=str(lab_dir), EJSWEB_IO=str(io_dir),
               PYTHONDONTWRITEBYTECODE="1")
    out_path, err_path = io_dir / "trace.out", io_dir / "trace.err"
    with open(out_path, "w+b") as out, open(err_path, "w+b") as err:
        proc = subprocess.Popen([sys.executable, "-c", _SCRIPT], env=env, stdout=out, stderr=err, cwd=str(io_dir))
        ended, slow = _watch(proc, err_path, timeout)
        stdout, stderr = out_path.read_text(errors="replace"), err_path.read_text(errors="replace")
    if not ended and slow is not None:
        where, _, _ = slow.partition(": warning:")
        place = f"{where}: " if ".ejs." in where else ""
        raise TraceError(f"{place}error: init: did not end within {INIT_GRACE:g} s after it was said to be slow "
                         "(an endless loop?), so the build could not run the lab to find what it imports")
    if not ended:
        raise TraceError(f"error: running the lab to find what it imports took longer than {timeout:g} s and was stopped")
    for line in reversed(stdout.split("\n")):  # not splitlines(): it splits at \x1e too
        if line.startswith("\x1e"):
            loaded = list(json.loads(line[1:]))
            return loaded + sorted(stdlib_imports(lab_dir, loaded, set(there) & set(sys.stdlib_module_names)) - set(loaded))
    raise TraceError(f"error: running the lab to find what it imports failed:\n{stderr[-3000:]}")


def _watch(proc: subprocess.Popen[bytes], err_path: Path, timeout: float) -> tuple[bool, str | None]:
    """Wait for the traced run; echo its slow-``init:`` warning when it comes; kill it
    :data:`INIT_GRACE` s after that or past ``timeout``. Returns whether it ended by itself,
    and the warning (None if there was none)."""
    start, said, line = time.monotonic(), None, None
    try:
        while proc.poll() is None:
            now = time.monotonic()
            if said is None:
                text = err_path.read_text(errors="replace")
                if _SLOW in text:
                    line = next(x for x in text.splitlines() if _SLOW in x)
                    print(line, file=sys.stderr, flush=True)
                    said = now
            if (said is not None and now - said > INIT_GRACE) or now - start > timeout:
                proc.kill()
                proc.wait()
                return False, line
            time.sleep(0.2)
    except BaseException:  # Ctrl+C: the traced run goes too
        proc.kill()
        proc.wait()
        raise
    return True, line


#: the top-level packages of a lab's own bundle (not the standard library's)
_LAB_PACKAGES = {"ejsrl", "viser", "trimesh", "app"}


def stdlib_imports(lab_dir: Path, loaded: list[str], stdlib: set[str]) -> set[str]:
    """The modules of the standard library (top-level names in ``stdlib``: the browser's that this
    Python knows as its own, not a third-party package of the zip) that the lab's own
    modules seen loading (``loaded``: dotted names; their files under ``lab_dir``) import
    anywhere in their code, inside functions too: a branch the traced run did not take (an
    export, an error's message) then still finds its module in the page."""
    from ejsgen._web_stdlib import imported_names

    files = []
    for name in loaded:
        if name.split(".")[0] not in _LAB_PACKAGES:
            continue
        base = lab_dir.joinpath(*name.split("."))
        for f in (base.with_suffix(".py"), base / "__init__.py"):
            if f.is_file():
                files.append(f)
    return {n for n in imported_names(files) if n.split(".")[0] in stdlib}
