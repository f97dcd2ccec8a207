"""Before an app imports its packages: name the missing ones and the one command that installs them.

A generated ``app.py`` ends with its inline script metadata (PEP 723)::

    # /// script
    # requires-python = ">=3.11"
    # dependencies = ["numpy>=1.26", "viser>=1.1,<1.2", ...]
    # [tool.ejsrl]
    # serve-only = ["viser"]
    # ///

so ``uv run app.py`` or ``pipx run app.py`` install them and run it on a machine with only
Python (the ``ejsrl`` folder, this runtime, stays beside app.py: it is not on PyPI). Only
the lab's own packages are listed (OpenCV only for a lab that uses it), and ``--headless``,
``--sweep`` and ``--help`` do not demand the ``serve-only`` ones. Run with plain ``python app.py`` (or a ``.pyz``) where some are missing, the app
used to die with ``ModuleNotFoundError: No module named 'numpy'``; ``require_packages``
(called by ``import ejsrl``, with the standard library only, before anything imports NumPy)
reads that list from the app's own file and, when a package is missing, prints which and the command, and exits 1.
"""

from __future__ import annotations

import importlib.util
import re
import shlex
import sys
import zipfile
from pathlib import Path

__all__ = ["require_packages", "dependencies_of", "serve_only_of", "serving", "missing", "check_main"]

_BLOCK = re.compile(r"(?m)^# /// script$\s(?P<content>(^#(| .*)$\s)+)^# ///$")
_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)")
#: distributions whose module has another name
_MODULES = {"opencv-python-headless": "cv2", "opencv-python": "cv2", "paho-mqtt": "paho", "pyyaml": "yaml", "pillow": "PIL"}


def _source(app_file: str) -> str | None:
    """The text of ``app_file``, also inside a ``.pyz`` (``lab.pyz/app.py``)."""
    path = Path(app_file)
    try:
        return path.read_text(encoding="utf-8")
    except OSError:
        pass
    for parent in path.parents:
        if parent.is_file() and zipfile.is_zipfile(parent):
            with zipfile.ZipFile(parent) as zf:
                try:
                    return zf.read(path.relative_to(parent).as_posix()).decode("utf-8")
                except KeyError:
                    return None
    return None


def _metadata(text: str) -> dict:  # type: ignore[type-arg]  # TOML: values of any type
    """The TOML of a script's PEP 723 block (``{}`` if it has none, or not valid TOML)."""
    import tomllib

    m = _BLOCK.search(text)
    if m is None:
        return {}
    toml = "".join(line[2:] if line.startswith("# ") else line[1:] for line in m.group("content").splitlines(keepends=True))
    try:
        return tomllib.loads(toml)
    except tomllib.TOMLDecodeError:
        return {}


def dependencies_of(text: str) -> list[str]:
    """The ``dependencies`` of a script's PEP 723 block (``[]`` if it has none)."""
    return [str(d) for d in _metadata(text).get("dependencies", [])]


def serve_only_of(text: str) -> set[str]:
    """The distributions (lower case) that only serving the app imports: the block's
    ``[tool.ejsrl] serve-only`` list (``--headless``, ``--sweep`` and ``--help`` run without them)."""
    tool = _metadata(text).get("tool", {}).get("ejsrl", {})
    return {str(name).lower() for name in tool.get("serve-only", [])} if isinstance(tool, dict) else set()


def serving(argv: list[str]) -> bool:
    """Whether an app's command line (``sys.argv[1:]``) serves its web UI: not ``--headless``,
    ``--sweep`` nor ``--help``."""
    return not any(arg in ("--headless", "--sweep", "--help", "-h") for arg in argv)


def _name(requirement: str) -> str:
    """The distribution's name in a requirement (``"viser>=1.1,<1.2"`` -> ``"viser"``; ``""`` if none)."""
    m = _NAME.match(requirement)
    return m.group(1) if m else ""


def missing(requirements: list[str]) -> list[str]:
    """The requirements whose distribution is not installed (nor its module importable)."""
    out = []
    for req in requirements:
        name = _name(req)
        if not name:
            continue
        module = _MODULES.get(name.lower(), name.replace("-", "_"))
        try:
            if importlib.util.find_spec(module) is not None:
                continue
        except (ImportError, ValueError):  # a finder that refuses it, or a module without a spec
            pass
        from importlib import metadata  # only then: importing it costs every app's start more than the check

        try:
            metadata.distribution(name)
        except metadata.PackageNotFoundError:
            out.append(req)
    return out


def require_packages(app_file: str | None = None, *, serve: bool = True) -> None:
    """Exit with a message naming the missing packages of ``app_file``'s list (default: the
    calling module's file) and the command that installs them all (nothing happens when none
    is missing, or when the code has no file, e.g. ``exec`` of its text). ``serve=False``
    (headless, a sweep, ``--help``): the list's ``serve-only`` packages may be missing."""
    if app_file is None:
        app_file = sys._getframe(1).f_globals.get("__file__")
    if app_file is None:
        return
    text = _source(app_file)
    if text is None:
        return
    requirements = dependencies_of(text)
    skip = set() if serve else serve_only_of(text)
    lacking = missing([r for r in requirements if _name(r).lower() not in skip])
    if not lacking:
        return
    names = ", ".join(_name(r) for r in lacking)
    folder = Path(app_file).parent
    archive = folder.is_file()  # app.py inside a .pyz
    listed = folder / "requirements.txt"
    if listed.is_file():
        command = f"{Path(sys.executable).name} -m pip install -r {shlex.quote(str(listed))}"
    else:
        command = f"{Path(sys.executable).name} -m pip install " + " ".join(shlex.quote(r) for r in requirements)
    tools = "" if archive else "\n(or run it with `uv run app.py` or `pipx run app.py`, which install what the end of app.py lists)"
    print(f"{folder.name if archive else Path(app_file).name}: this app needs Python packages that are not installed: {names}\n"
          f"install them with:\n    {command}{tools}", file=sys.stderr)
    raise SystemExit(1)


def check_main() -> None:
    """``require_packages`` for the running program when it is a generated app (``python app.py``
    or a ``.pyz``, whose ``app.py`` is inside): called when ``ejsrl`` is first imported, before
    anything imports NumPy; programs without inline script metadata are left alone."""
    try:
        main_file = getattr(sys.modules.get("__main__"), "__file__", None)
        if not main_file:
            return
        path = Path(main_file)
        app = path.parent / "app.py" if path.parent.is_file() else path  # in a .pyz: its app.py
        text = _source(str(app))
        if text is None or "# /// script" not in text:
            return
    except Exception:  # noqa: BLE001 - a check that must never stop an import
        return
    require_packages(str(app), serve=serving(sys.argv[1:]))
