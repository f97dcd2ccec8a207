"""The files a spec lists under ``assets:``, found wherever the app runs.

A generated ``app.py`` whose code opens an asset binds ``asset = app_assets(__file__)``:
``asset('measured.csv')`` is then the absolute path of that file, whether the app runs from
its folder, from another working directory, headless, in a sweep's worker process or Dask
worker (each imports ``app.py`` from a folder holding its assets), or from a single-file
``.pyz``. The compiler writes ``asset('measured.csv')`` for every string in spec code that
is exactly an asset's path, so ``np.loadtxt('measured.csv')`` reads the app's own file.

A ``.pyz`` carries its assets and a manifest (:data:`MANIFEST`: each asset's SHA-256 and
size). They are extracted once into a per-user cache folder named by a digest of the
manifest (so by the assets' content), read-only, and moved into place in one step: two
processes starting at once never see a half-written folder, and an archive whose assets
changed gets a folder of its own.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import stat
import sys
import tempfile
import zipfile
from pathlib import Path, PurePosixPath

__all__ = ["AppAssets", "app_assets", "bundle_assets", "asset_cache_root", "manifest_of", "MANIFEST"]

#: the manifest of a ``.pyz``'s assets: ``{"files": {name: {"sha256": hex, "size": bytes}}}``
MANIFEST = "ejsgen-assets.json"


class AppAssets:
    """``asset(name)``: the absolute path (``str``) of the asset ``name`` of one app.

    ``folder``: where the app's assets are (the app's folder, or a ``.pyz``'s cache folder).
    ``name`` is the path the spec lists under ``assets:`` (relative, ``/``-separated);
    a name that leaves the folder (``..``, an absolute path) raises ``ValueError``, a file
    that is not there ``FileNotFoundError``, both saying which name and where it was looked for.
    """

    def __init__(self, folder: Path | str) -> None:
        self.folder = Path(folder)

    def __call__(self, name: str | os.PathLike[str]) -> str:
        text = os.fspath(name)
        if not isinstance(text, str) or not text:
            raise ValueError(f"asset(): give the asset's path as text, e.g. asset('data.csv'), not {name!r}")
        if Path(text).is_absolute() and Path(text).is_relative_to(self.folder):  # a path asset() gave already
            text = Path(text).relative_to(self.folder).as_posix()
        rel = PurePosixPath(text.replace("\\", "/"))
        if rel.is_absolute() or Path(text).is_absolute() or ".." in rel.parts:
            raise ValueError(f"asset('{text}'): an asset is named by its path relative to the spec, inside the spec's folder")
        path = self.folder / rel
        if not path.is_file():
            raise FileNotFoundError(f"asset('{text}'): no such file among the app's assets ({self.folder}); is it listed under 'assets:' in the spec?")
        return str(path)

    def __repr__(self) -> str:
        return f"AppAssets({str(self.folder)!r})"


def app_assets(app_file: str | os.PathLike[str]) -> AppAssets:
    """The assets of the app whose ``app.py`` is ``app_file`` (its ``__file__``).

    A folder app's assets are beside ``app.py``; an ``app.py`` inside a ``.pyz``
    (``.../lab.pyz/app.py``) has them extracted by :func:`bundle_assets`.
    """
    path = Path(os.path.abspath(os.fspath(app_file)))
    archive = _archive_of(path)
    if archive is None:
        return AppAssets(path.resolve().parent)
    return AppAssets(bundle_assets(archive))


def _archive_of(path: Path) -> Path | None:
    """The zip archive that ``path`` lies inside (``lab.pyz`` for ``lab.pyz/app.py``), or None."""
    if path.exists():
        return None
    for parent in path.parents:
        if parent.is_file():
            return parent if zipfile.is_zipfile(parent) else None
        if parent.exists():
            return None
    return None


def asset_cache_root() -> Path:
    """This user's cache of extracted assets: ``$XDG_CACHE_HOME/ejsgen/assets`` (``~/.cache``
    by default; ``%LOCALAPPDATA%`` on Windows), else a folder of this user's in the system's
    temporary folder. Made readable by this user only."""
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
    else:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    candidates = [Path(base) / "ejsgen" / "assets"]
    uid = os.getuid() if hasattr(os, "getuid") else os.getpid()
    candidates.append(Path(tempfile.gettempdir()) / f"ejsgen-assets-{uid}")
    for root in candidates:
        try:
            root.mkdir(parents=True, exist_ok=True, mode=0o700)
            if os.access(root, os.W_OK | os.X_OK) and _ours(root):
                return root
        except OSError:
            continue
    raise OSError("no writable folder for the app's assets: set XDG_CACHE_HOME to a folder you can write")


def _ours(folder: Path) -> bool:
    """Whether ``folder`` is this user's and no one else may write into it (a folder someone
    else made in the shared temporary folder, to plant files there, is not used)."""
    if not hasattr(os, "getuid"):
        return True
    st = folder.lstat()
    return stat.S_ISDIR(st.st_mode) and st.st_uid == os.getuid() and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def bundle_assets(archive: Path | str) -> Path:
    """The folder holding the assets of the ``.pyz`` ``archive``, extracted on first use.

    The folder is named by a digest of the archive's manifest (:data:`MANIFEST`); each file
    is checked against its SHA-256 as it is written, made read-only, and the folder is moved
    into place in one rename. A folder already there is used when every file has its size.
    """
    path = Path(archive).resolve()
    st = path.stat()
    return _bundle_assets(path, st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=16)
def _bundle_assets(archive: Path, _mtime_ns: int, _size: int) -> Path:
    with zipfile.ZipFile(archive) as zf:
        try:
            raw = zf.read(MANIFEST)
        except KeyError:
            raw = b'{"files": {}}'
        files: dict[str, dict[str, object]] = json.loads(raw.decode("utf-8")).get("files", {})
        for name in files:
            _check_name(name)
        if not files:  # nothing to extract: no folder made
            return archive.parent
        root = asset_cache_root()
        final = root / hashlib.sha256(raw).hexdigest()[:24]
        if _complete(final, files):
            return final
        tmp = Path(tempfile.mkdtemp(prefix=".incoming-", dir=root))
        try:
            for name, info in files.items():
                data = zf.read(name)
                if hashlib.sha256(data).hexdigest() != info.get("sha256"):
                    raise OSError(f"{archive}: the asset '{name}' does not match the archive's manifest (a damaged .pyz?)")
                target = tmp / name
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
                target.chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
            _move_into_place(tmp, final, files)
        finally:
            if tmp.exists():
                shutil.rmtree(tmp, ignore_errors=True)
    return final


def _check_name(name: str) -> None:
    rel = PurePosixPath(name)
    if not name or rel.is_absolute() or ".." in rel.parts or "\\" in name:
        raise OSError(f"the archive's manifest names '{name}', which is not a path inside the app")


def _complete(folder: Path, files: dict[str, dict[str, object]]) -> bool:
    """Whether ``folder`` holds every file of the manifest, each of its size."""
    if not folder.is_dir():
        return False
    for name, info in files.items():
        p = folder / name
        try:
            if not p.is_file() or p.is_symlink() or p.stat().st_size != info.get("size"):
                return False
        except OSError:
            return False
    return True


def _move_into_place(tmp: Path, final: Path, files: dict[str, dict[str, object]]) -> None:
    """Rename ``tmp`` to ``final``; a complete folder another process put there first wins,
    an incomplete one (files deleted since) is replaced."""
    try:
        tmp.rename(final)
        return
    except OSError:
        if _complete(final, files):
            return
    stale = final.with_name(f".stale-{final.name}-{os.getpid()}")
    try:
        final.rename(stale)
    except OSError:
        pass
    try:
        tmp.rename(final)
    except OSError:
        if not _complete(final, files):
            raise
    shutil.rmtree(stale, ignore_errors=True)


def manifest_of(files: dict[str, Path]) -> bytes:
    """The manifest (:data:`MANIFEST`) of the assets ``files`` (archive name -> file), for a ``.pyz``."""
    out = {}
    for name in sorted(files):
        data = Path(files[name]).read_bytes()
        out[name] = {"sha256": hashlib.sha256(data).hexdigest(), "size": len(data)}
    return json.dumps({"files": out}, indent=1, sort_keys=True).encode("utf-8")
