"""What ``ejsgen build --web`` refuses: the parts of a spec that cannot run in a browser.

A web build runs the lab in the student's browser, on a WebAssembly Python that has the
standard library, NumPy and SciPy (and lxml, for a lab that reads URDF files) (issue #32).
It has no OpenCV, no way to load a native library, no sockets, no threads and no processes. :func:`web_refusals` lists every feature of a spec that needs one of those, each
as a :class:`~ejsgen.errors.SpecError` at the spec's line and column that asks for it,
naming the feature, saying why, and what to do (serve the lab instead):

- OpenCV: a camera's real image ``source:``, its ``blur`` and lens ``distortion``, marker
  textures, the OpenCV functions of ``ejsrl.vision`` (and ``cv2``) in ``imports:`` or code,
  ``ImageSource``, and an ``OccupancyGrid.from_image`` of a file. Virtual cameras themselves
  render with NumPy, and their images are shown by ``image`` elements as served, with their
  ``points`` (drawn with NumPy); a 2D ``image`` runs too: an array is drawn as served, and a ``file:``
  (PNG, JPEG, ...) is decoded by the build (:func:`web_image_files`), so only a file OpenCV
  cannot read is refused;
- native code: every FMU under ``fmus:`` (FMPy loads the FMU's binary; an FMU kept as C
  sources is compiled to one), COLLADA and 3MF meshes (pycollada; lxml and networkx), and
  third-party packages other than NumPy and SciPy in ``imports:`` or code. URDF robots run:
  the page gets yourdfpy's Python and lxml's (``ejsgen._web_build.uses_urdf``);
- the network, threads and processes: a remote plant (``plant:``), and the standard
  library's sockets, threads, processes and native calls (:data:`NO_BROWSER_STDLIB`);
- data: the files the spec names (``assets:``, meshes, images, FMUs) beyond
  :data:`DATA_LIMIT_BYTES` in all, which every student would download on a first visit.

Sweeps (``ejsgen sweep``, on processes or Dask) are a command, not part of a lab: a web
build keeps ``metrics:`` and runs no sweep, so nothing there is refused.
"""

from __future__ import annotations

import ast
import functools
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ejsgen.errors import SpecError
from ejsgen.yamlload import Path_

if TYPE_CHECKING:
    from ejsgen.validate import Checked
    from ejsgen.yamlload import Document

__all__ = ["web_refusals", "web_image_files", "DATA_LIMIT_BYTES", "BROWSER_PACKAGES", "NO_BROWSER_STDLIB", "opencv_names"]

#: the most data (bytes, on disk) a web build ships: the files the spec names, in all
DATA_LIMIT_BYTES = 20 * 1024 * 1024
#: the third-party packages the browser's Python has (with the standard library)
BROWSER_PACKAGES = ("numpy", "scipy", "ejsrl")
#: standard-library modules that import in the browser but cannot work there -> what they need
NO_BROWSER_STDLIB = {
    "socket": "network sockets", "ssl": "network sockets", "socketserver": "network sockets",
    "http.client": "network sockets", "http.server": "network sockets", "urllib.request": "network sockets",
    "ftplib": "network sockets", "smtplib": "network sockets",
    "threading": "threads", "_thread": "threads", "concurrent": "threads and processes",
    "subprocess": "processes", "multiprocessing": "processes", "ctypes": "native libraries",
    "tkinter": "a desktop window", "webbrowser": "a desktop browser",
}  # fmt: skip
#: ejsrl modules a web build cannot run -> the feature and why (their names, imported)
NO_BROWSER_EJSRL = {
    "ejsrl.fmi": "FMPy loads each FMU's native binary, and a browser cannot load a native library",
    "ejsrl.plant": "a remote plant is driven over the network (MQTT or OPC UA), and a page's Python has no sockets",
    "ejsrl.app.sweep": "sweeps run on processes or Dask, which a page's Python cannot start",
    "ejsrl.vision.sources": "cameras, streams and videos are read by OpenCV and the devices of the machine that runs the lab",
}
#: names (in imports or code) that need what a browser lacks -> the feature and why
NO_BROWSER_NAMES = {
    "ImageSource": NO_BROWSER_EJSRL["ejsrl.vision.sources"],
}
#: mesh formats trimesh reads through packages a page does not get -> why
LXML_MESHES = {
    ".dae": ".dae (COLLADA) meshes are read through pycollada, which the browser's Python lacks",
    ".3mf": ".3mf meshes are read through lxml and networkx, which a web build does not ship",
}

_WHY_OPENCV = "OpenCV, which the browser's Python does not have"
_SERVE = "serve this lab instead (`ejsgen run SPEC`, or `python app.py --host 0.0.0.0` for a class: each tab gets its own simulation)"


def web_refusals(checked: Checked, spec_path: Path) -> list[SpecError]:
    """Every feature of ``checked`` (a validated spec, loaded from ``spec_path``) that cannot
    run in a browser, in file order; ``[]`` when the whole lab can."""
    doc = checked.doc
    data = doc.data if isinstance(doc.data, dict) else {}
    spec_dir = Path(spec_path).resolve().parent
    out: list[SpecError] = []
    out += _import_refusals(doc, data.get("imports") or [])
    out += _code_refusals(doc)
    out += _view_refusals(doc, data.get("view") or [])
    for name in data.get("fmus") or {}:
        out.append(_fmu_refusal(doc, name, data["fmus"][name], spec_dir))
    if data.get("plant") is not None:
        out.append(_refusal(doc, ("plant",), "a remote plant (`plant:`)",
                            "the lab drives it over the network (MQTT or OPC UA), and a page's Python has no sockets", key=True))
    out += _image_refusals(doc, data, spec_dir)
    out += _data_refusals(doc, data, spec_dir)
    unique = {(str(e.where), e.message): e for e in out}
    return sorted(unique.values(), key=lambda e: (e.where.line, e.where.col))


def _refusal(doc: Document, path: Path_, feature: str, why: str, *, key: bool = False, hint: str = _SERVE) -> SpecError:
    where = doc.key_loc(path) if key else doc.loc(path)
    return SpecError(where, f"{feature} cannot run in a browser (`--web`): {why}", hint)


# -- imports and code ----------------------------------------------------------------------------


@functools.cache
def _vision_tables() -> tuple[frozenset[str], dict[str, str]]:
    """(the ``ejsrl.vision`` modules that import OpenCV, {public name: module} of those that do),
    read from the package's sources without importing OpenCV."""
    import ejsrl

    root = Path(ejsrl.__file__).resolve().parent / "vision"
    needs = _opencv_modules(root)
    exports = _lazy_exports(root / "__init__.py")
    return frozenset(needs), {name: module for name, module in exports.items() if module in needs}


def opencv_names() -> dict[str, str]:
    """``ejsrl.vision``'s public names that need OpenCV -> the module defining each."""
    return _vision_tables()[1]


def _opencv_modules(root: Path) -> set[str]:
    """The modules of the ``ejsrl.vision`` package at ``root`` that import OpenCV when imported
    (``import cv2`` at their top, or a module that does)."""
    deps: dict[str, set[str]] = {}
    for path in root.glob("*.py"):
        name = "ejsrl.vision" if path.stem == "__init__" else f"ejsrl.vision.{path.stem}"
        tree = ast.parse(path.read_text(encoding="utf-8"))
        mods: set[str] = set()
        for node in tree.body:  # the top only: imports inside functions happen when those run
            if isinstance(node, ast.Import):
                mods.update(a.name for a in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module:
                base = node.module if node.level == 0 else "ejsrl.vision" + (f".{node.module}" if node.module else "")
                mods.add(base)
                mods.update(f"{base}.{a.name}" for a in node.names)
        deps[name] = mods
    needs = {name for name, mods in deps.items() if "cv2" in mods}
    while True:
        more = {name for name, mods in deps.items() if name not in needs and mods & needs}
        if not more:
            return needs
        needs |= more


def _lazy_exports(init: Path) -> dict[str, str]:
    """name -> module of the ``lazy_exports(__name__, {...})`` table in a package's ``__init__``."""
    out: dict[str, str] = {}
    for node in ast.walk(ast.parse(init.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "lazy_exports" and len(node.args) == 2:
            table = ast.literal_eval(node.args[1])
            for module, names in table.items():
                for name in names:
                    out[name] = "ejsrl.vision" + module if module.startswith(".") else module
    return out


def _module_refusal(module: str, names: list[str]) -> tuple[str, str] | None:
    """(feature, why) when importing ``names`` from ``module`` (``[]``: the module itself)
    cannot work in a browser; else None."""
    top = module.partition(".")[0]
    if top == "cv2":
        return "OpenCV (`cv2`)", "the browser's Python has no OpenCV"
    for mod, why in NO_BROWSER_EJSRL.items():
        if module == mod or module.startswith(mod + "."):
            return f"`{module}`", why
    if top == "ejsrl":
        modules, opencv = _vision_tables()
        named = [n for n in names if n in NO_BROWSER_NAMES]
        if named:
            return f"`{named[0]}`", NO_BROWSER_NAMES[named[0]]
        if module.startswith("ejsrl.vision"):
            if not names and module in modules:
                return f"`{module}`", f"its image functions run on {_WHY_OPENCV}"
            bad = [n for n in names if n in opencv or module in modules]
            if bad:
                return f"`{', '.join(bad)}` from `{module}`", f"{'they run' if len(bad) > 1 else 'it runs'} on {_WHY_OPENCV}"
        return None
    for mod, why in NO_BROWSER_STDLIB.items():
        if module == mod or module.startswith(mod + "."):
            return f"`{module}`", f"it needs {why}, which a page's Python does not have"
    if top in sys.stdlib_module_names or top in BROWSER_PACKAGES or top == "__future__":
        return None
    return f"the package `{top}`", "the browser's Python has the standard library, NumPy and SciPy only (no other package is shipped)"


def _import_statements(tree: ast.AST) -> Iterator[tuple[ast.stmt, str, list[str]]]:
    """(statement, module, names) of every import in ``tree`` (names ``[]`` for ``import m``)."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield node, alias.name, []
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names = [a.name for a in node.names]
            if node.module in ("ejsrl", "ejsrl.robotics", "ejsrl.vision", "ejsrl.app"):  # a submodule by name
                subs = [n for n in names if f"{node.module}.{n}" in NO_BROWSER_EJSRL or f"{node.module}.{n}" in _vision_tables()[0]]
                for sub in subs:
                    yield node, f"{node.module}.{sub}", []
                names = [n for n in names if n not in subs]
            yield node, node.module, names


def _import_refusals(doc: Document, imports: list[Any]) -> list[SpecError]:
    out = []
    for i, line in enumerate(imports):
        try:
            tree = ast.parse(str(line))
        except SyntaxError:
            continue  # reported by the build itself
        for _, module, names in _import_statements(tree):
            found = _module_refusal(module, names)
            if found is not None:
                out.append(_refusal(doc, ("imports", i), found[0], found[1]))
    return out


def _vision_aliases(doc: Document) -> set[str]:
    """Names the spec's ``imports:`` bind to ``ejsrl.vision`` (``import ejsrl.vision as V``,
    ``from ejsrl import vision``)."""
    out = set()
    for line in (doc.data.get("imports") or []) if isinstance(doc.data, dict) else []:
        try:
            tree = ast.parse(str(line))
        except SyntaxError:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                out.update(a.asname for a in node.names if a.name == "ejsrl.vision" and a.asname)
            elif isinstance(node, ast.ImportFrom) and node.module == "ejsrl":
                out.update(a.asname or a.name for a in node.names if a.name == "vision")
    return out


def _code_refusals(doc: Document) -> list[SpecError]:
    """Imports in code, OpenCV functions reached through a ``vision`` module name and map images
    read from files, at their place in the code."""
    from ejsgen._resolve import Snippet

    aliases = _vision_aliases(doc)
    opencv = opencv_names()
    out = []
    for path, origin in doc.origins.items():
        if not path or path[0] in ("imports", "title", "description", "author", "assets"):
            continue
        text = _value_at(doc.data, path)
        if not isinstance(text, str) or not any(c in text for c in "(.") and "import" not in text:
            continue
        try:
            tree = ast.parse(text)
        except SyntaxError:
            continue
        snippet = Snippet(text, origin, doc.file, "code")
        for node in ast.walk(tree):
            found = None
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                for _, module, names in _import_statements(node):
                    found = found or _module_refusal(module, names)
            elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
                if node.value.id in aliases and node.attr in opencv:
                    found = (f"`{node.value.id}.{node.attr}`", f"it runs on {_WHY_OPENCV}")
                elif node.attr in NO_BROWSER_NAMES:
                    found = (f"`{node.attr}`", NO_BROWSER_NAMES[node.attr])
            elif isinstance(node, ast.Call) and _called_name(node) == "from_image" and node.args \
                    and isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                found = ("a map read from an image file (`from_image`)", f"image files are read by {_WHY_OPENCV}")
            if found is not None:
                where = snippet.location(getattr(node, "lineno", 1), getattr(node, "col_offset", 0))
                out.append(SpecError(where, f"{found[0]} cannot run in a browser (`--web`): {found[1]}", _SERVE))
    return out


def _called_name(call: ast.Call) -> str:
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else ""


def _value_at(data: Any, path: Path_) -> Any:
    for key in path:
        try:
            data = data[key]
        except (KeyError, IndexError, TypeError):
            return None
    return data


# -- the view ------------------------------------------------------------------------------------

_UNREADABLE_WHY = ("the build decodes it for the page with OpenCV, which cannot read this file (not an image, or a "
                   "format this OpenCV has no decoder for)")
_SOURCE_WHY = ("cameras, streams and video files are read by OpenCV and the devices of the machine that runs "
               "the lab; a page's Python has neither")
#: a camera's properties that need OpenCV when set -> the feature and why
_CAMERA_OPENCV = {
    "blur": ("a camera's defocus `blur`", f"it is OpenCV's Gaussian blur, on {_WHY_OPENCV}"),
    "distortion": ("a camera's lens `distortion`", f"the image is remapped by {_WHY_OPENCV}"),
}
_MARKER_WHY = "marker images are drawn by OpenCV's ArUco module, which the browser's Python does not have"


def _set(value: Any) -> bool:
    """Whether a property is on: given, and not a constant 0 (or a list of zeros)."""
    if value is None or value is False:
        return False
    if isinstance(value, (int, float)):
        return value != 0
    if isinstance(value, list):
        return any(_set(v) for v in value)
    return True  # an expression: its value is known only when the lab runs


def _items(doc: Document, items: Any, path: Path_, where: str) -> Iterator[tuple[str, Any, Path_, str]]:
    """(kind, properties, path of the item, "panel" | "3d" | "2d") of every element, nested ones too."""
    if not isinstance(items, list):
        return
    for i, item in enumerate(items):
        if not isinstance(item, dict) or len(item) != 1:
            continue
        kind, props = next(iter(item.items()))
        ipath = (*path, i)
        yield kind, props, ipath, where
        if where == "panel" and kind == "scene":
            yield from _items(doc, props, (*ipath, kind), "3d")
        elif not isinstance(props, dict):
            continue
        elif kind == "tabs" and isinstance(props.get("tabs"), dict):
            for label, children in props["tabs"].items():
                yield from _items(doc, children, (*ipath, kind, "tabs", label), where)
        elif "children" in props:
            inner = "2d" if kind == "drawing" else where
            yield from _items(doc, props["children"], (*ipath, kind, "children"), inner)


def _view_refusals(doc: Document, view: Any) -> list[SpecError]:
    """A camera's real ``source``, ``blur`` and ``distortion``,
    marker textures, and COLLADA and 3MF meshes. Virtual cameras themselves render with
    NumPy, and image elements are shown as served (a 2D image's file: :func:`_image_refusals`)."""
    out = []
    for kind, props, path, where in _items(doc, view, ("view",), "panel"):
        at = (*path, kind)
        props = props if isinstance(props, dict) else {}
        if where != "3d":
            continue
        if kind == "camera" and props.get("source") is not None:
            out.append(_refusal(doc, (*at, "source"), "a real image source (a camera's `source:`)", _SOURCE_WHY, key=True))
        for key, (feature, why) in _CAMERA_OPENCV.items() if kind == "camera" else ():
            if _set(props.get(key)):
                out.append(_refusal(doc, (*at, key), feature, why, key=True, hint=f"leave `{key}` out, or " + _SERVE))
        texture = props.get("texture")
        if isinstance(texture, str) and ":" in texture:
            out.append(_refusal(doc, (*at, "texture"), f"the marker texture '{texture}'", _MARKER_WHY, key=True))
        for key, file in _mesh_files(kind, props):
            if Path(file).suffix.lower() in LXML_MESHES:
                out.append(_refusal(doc, (*at, *key), f"the mesh '{file}'", LXML_MESHES[Path(file).suffix.lower()],
                                    key=True, hint="convert it to GLB, OBJ or STL (e.g. in Blender), or " + _SERVE))
    return out


def _mesh_files(kind: str, props: dict[str, Any]) -> Iterator[tuple[tuple[Any, ...], str]]:
    """(key path inside the element, file) of each mesh file a 3D element names."""
    if kind == "mesh" and isinstance(props.get("file"), str):
        yield ("file",), props["file"]
    if kind == "robot" and isinstance(props.get("meshes"), list):
        for i, f in enumerate(props["meshes"]):
            if isinstance(f, str):
                yield ("meshes", i), f


def _image_files(doc: Document, view: Any) -> Iterator[tuple[Path_, str]]:
    """(path of the ``file`` key in the spec, file) of every 2D ``image`` element's file."""
    for kind, props, path, where in _items(doc, view, ("view",), "panel"):
        if where == "2d" and kind == "image" and isinstance(props, dict) and isinstance(props.get("file"), str):
            yield (*path, kind, "file"), props["file"]


def web_image_files(checked: Checked) -> list[str]:
    """The files (relative to the spec, as written) of the spec's 2D ``image`` elements: the
    web build writes each one's decoded copy for the page (:mod:`ejsrl.view._image_file`)."""
    data = checked.doc.data if isinstance(checked.doc.data, dict) else {}
    return sorted({rel for _path, rel in _image_files(checked.doc, data.get("view") or [])})


def _image_refusals(doc: Document, data: dict[str, Any], spec_dir: Path) -> list[SpecError]:
    """A 2D image's file that OpenCV cannot read, so the build could not decode it for the page
    (a missing file is the normal build's error)."""
    files = list(_image_files(doc, data.get("view") or []))
    if not files:
        return []
    import cv2

    out = []
    for path, rel in files:
        file = spec_dir / rel
        if file.is_file() and not cv2.haveImageReader(str(file)):
            out.append(_refusal(doc, path, f"the image file '{rel}'", _UNREADABLE_WHY, key=True,
                                hint="convert it to PNG (or JPEG), or " + _SERVE))
    return out


# -- FMUs and data -------------------------------------------------------------------------------


def _fmu_refusal(doc: Document, name: str, fmu: Any, spec_dir: Path) -> SpecError:
    file = fmu.get("file") if isinstance(fmu, dict) else None
    parts = _fmu_parts(spec_dir / file) if isinstance(file, str) else set()
    if "binaries" in parts:
        why = "FMPy runs its native binary (binaries/ in the FMU), and a browser cannot load a native library"
    elif "sources" in parts:
        why = "its C sources are compiled to a native library for this machine, which a browser cannot load"
    else:
        why = "FMPy runs an FMU's native binary, and a browser cannot load a native library"
    return _refusal(doc, ("fmus", name), f"the FMU '{name}'", why, key=True)


def _fmu_parts(path: Path) -> set[str]:
    """The top-level folders of an FMU (an ``.fmu`` archive or an unpacked folder)."""
    try:
        if path.is_dir():
            return {p.name for p in path.iterdir() if p.is_dir()}
        with zipfile.ZipFile(path) as zf:
            return {n.split("/", 1)[0] for n in zf.namelist() if "/" in n}
    except (OSError, zipfile.BadZipFile):
        return set()


def _named_files(doc: Document, data: dict[str, Any]) -> Iterator[tuple[Path_, str]]:
    """(path in the spec, file) of every file the spec names: assets, meshes, images, FMUs,
    camera sources given as files."""
    for i, f in enumerate(data.get("assets") or []):
        yield ("assets", i), f
    for name, fmu in (data.get("fmus") or {}).items():
        if isinstance(fmu, dict) and isinstance(fmu.get("file"), str):
            yield ("fmus", name, "file"), fmu["file"]
    for kind, props, path, where in _items(doc, data.get("view") or [], ("view",), "panel"):
        if not isinstance(props, dict):
            continue
        if where == "3d":
            for key, file in _mesh_files(kind, props):
                yield (*path, kind, *key), file
            if kind == "camera" and isinstance(props.get("source"), str):
                yield (*path, kind, "source"), props["source"]
        elif where == "2d" and kind == "image" and isinstance(props.get("file"), str):
            yield (*path, kind, "file"), props["file"]


def _size(path: Path) -> int:
    """Bytes of a file, or of every file in a folder (0 if it cannot be read: the build says why)."""
    try:
        if path.is_dir():
            return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
        return path.stat().st_size if path.is_file() else 0
    except OSError:
        return 0


def _data_refusals(doc: Document, data: dict[str, Any], spec_dir: Path) -> list[SpecError]:
    """The file that takes the data past :data:`DATA_LIMIT_BYTES` (each file counted once)."""
    seen: set[Path] = set()
    total = 0
    files: list[tuple[int, str]] = []
    for path, rel in _named_files(doc, data):
        if not isinstance(rel, str):
            continue
        real = (spec_dir / rel).resolve()
        if real in seen or not real.is_relative_to(spec_dir):
            continue
        seen.add(real)
        size = _size(real)
        total += size
        files.append((size, rel))
        if total > DATA_LIMIT_BYTES:
            largest = ", ".join(f"'{r}' {s / 2**20:.1f} MB" for s, r in sorted(files, reverse=True)[:3])
            return [_refusal(doc, path, f"'{rel}'", f"with it the lab's files come to more than "
                             f"{DATA_LIMIT_BYTES // 2**20} MB ({largest}), which every student would download on a first visit",
                             hint="make the data smaller (fewer samples, a coarser mesh, compressed images), or " + _SERVE)]
    return []
