"""Check the files a spec names (assets, mesh files) before they are copied into an app.

A file is accepted only if its *real* path (every symbolic link followed) lies inside the
spec's folder, so a link such as ``link.obj -> /etc/passwd`` is never copied into an app
or its ``.pyz``. Every mesh file, and every asset with a mesh extension, is read with the
runtime's own loader (``ejsrl.world.mesh.load_mesh``), so a file the app could not show
is refused at build time, at the spec location that names it.

Spec code names an asset by its path (``np.loadtxt('measured.csv')``): the rewriter
(``ejsgen._resolve``) turns every string that is exactly a listed asset's path into
``asset('measured.csv')`` (:func:`asset_call`), the app's function that gives the file's
real path wherever the app runs (``ejsrl.app._assets``), and lets ``open`` read an asset
(:func:`opens_an_asset`), as it lets it read nothing else.
"""

from __future__ import annotations

import ast
import functools
import warnings
from pathlib import Path, PurePosixPath

from ejsgen.errors import Location, SpecError

__all__ = ["checked_asset", "urdf_meshes", "MESH_EXTENSIONS", "ASSET_FUNCTION", "asset_names", "asset_call", "opens_an_asset", "unlisted_file"]

#: extensions read as meshes by the runtime (``ejsrl.world.mesh``)
MESH_EXTENSIONS = ("obj", "stl", "ply", "glb", "gltf", "off", "dae", "3mf", "wrl", "wrz", "vrml")


def real_path_inside(spec_dir: Path, rel: str, where: Location, what: str, copy_hint: str) -> tuple[PurePosixPath, Path]:
    """``rel`` as a relative path and the real path it names, refused (``SpecError``) if it
    leaves the spec's folder directly, with ``..`` or through a symbolic link, or names
    nothing. ``copy_hint``: how the user brings the thing into the folder."""
    p = PurePosixPath(rel.replace("\\", "/"))
    if p.is_absolute() or Path(rel).is_absolute() or ".." in p.parts:
        raise SpecError(
            where,
            f"the {what} '{rel}' must be a path inside the spec's folder",
            f"{copy_hint} next to the spec (or into a subfolder) and name it relative to the spec",
        )
    folder = spec_dir.resolve()
    src = folder / p
    if not src.exists() and not src.is_symlink():
        raise SpecError(where, f"the {what} '{rel}' does not exist", "paths are relative to the spec's folder")
    try:
        real = src.resolve(strict=True)
    except (OSError, RuntimeError):  # a dangling or looping link
        raise SpecError(where, f"the {what} '{rel}' is a link to a file that does not exist") from None
    if not real.is_relative_to(folder):
        raise SpecError(
            where,
            f"the {what} '{rel}' is a link to a file outside the spec's folder",
            f"only files inside the spec's folder are copied into an app; {copy_hint} there instead of linking to it",
        )
    return p, real


def checked_asset(spec_dir: Path, rel: str, where: Location, what: str = "asset", *, mesh: bool = False) -> tuple[str, Path]:
    """Check the file ``rel`` named in the spec; returns (its posix relative path, its real path).

    ``spec_dir``: the spec's folder; ``where``: the spec location of the name, for errors;
    ``mesh``: the file must be a mesh the runtime can read (assets with a mesh extension
    are read too). Raises ``SpecError`` when the path leaves the spec's folder (directly,
    with ``..``, or through a symbolic link), does not name a regular file, or is a mesh
    that cannot be read.
    """
    p, real = real_path_inside(spec_dir, rel, where, what, "copy the file")
    if not real.is_file():
        kind = "a folder" if real.is_dir() else "not a regular file"
        raise SpecError(where, f"the {what} '{rel}' is {kind}", f"name a file{' (OBJ, STL, PLY, GLB/glTF, OFF or VRML97 .wrl)' if mesh else ''}")
    if mesh or p.suffix.lower().lstrip(".") in MESH_EXTENSIONS:
        _check_mesh(real, rel, where, what)
    return p.as_posix(), real


def urdf_meshes(spec_dir: Path, real: Path, rel: str, where: Location) -> list[str]:
    """The mesh files the URDF file ``rel`` (``real``: its real path, a listed asset) names, as
    paths relative to the spec's folder, found as the runtime finds them (``ejsrl.robotics.urdf``:
    a relative name beside the URDF file, ``package://pkg/rel`` as ``rel`` or ``pkg/rel`` there or
    in a parent folder), so that the app gets them too. A URDF that is not XML, or whose root is
    not ``<robot>``, or that names a mesh the spec's folder does not have, is a ``SpecError`` at
    ``where`` (found at build time: at run time a broken file read as a tree of several roots)."""
    import xml.etree.ElementTree as ET

    data = real.read_bytes()
    if b"<!ENTITY" in data or b"<!DOCTYPE" in data:
        raise SpecError(where, f"the URDF file '{rel}' declares a DOCTYPE or entities, which a robot description does not need",
                        "remove the <!DOCTYPE ...> / <!ENTITY ...> lines")
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        line, col = e.position
        raise SpecError(where, f"the URDF file '{rel}' is not well-formed XML: {str(e).split(':')[0]} at its line {line}, "
                        f"column {col + 1}", "fix the file (a missing closing tag, or a truncated file?)") from None
    if root.tag != "robot":
        raise SpecError(where, f"the URDF file '{rel}' has <{root.tag}> at its root, not <robot>", "name a URDF file (<robot name=...>)")
    folder = spec_dir.resolve()
    urdf_dir = real.parent
    out: list[str] = []
    for mesh in root.iter("mesh"):
        name = mesh.get("filename", "")
        for prefix in ("package://", "file://"):
            if name.startswith(prefix):
                name = name[len(prefix):]
                break
        parts = PurePosixPath(name.replace("\\", "/")).parts
        found = None
        if name and not PurePosixPath(name).is_absolute() and ".." not in parts:
            for base in [urdf_dir, *urdf_dir.parents]:
                if not base.is_relative_to(folder):
                    break
                for k in range(len(parts)):
                    p = base.joinpath(*parts[k:])
                    if p.is_file():
                        found = p
                        break
                if found is not None:
                    break
        if found is None or not found.resolve().is_relative_to(folder):
            raise SpecError(where, f"the URDF file '{rel}' names the mesh '{mesh.get('filename', '')}', which is not in the spec's folder",
                            "put the mesh beside the URDF file (or in a subfolder, as the URDF names it): the app is made only "
                            "from files inside the spec's folder")
        out.append(found.relative_to(folder).as_posix())  # found lies under the URDF's real folder
    return sorted(set(out))


def _check_mesh(real: Path, rel: str, where: Location, what: str) -> None:
    stat = real.stat()
    problem = _mesh_problem(real, stat.st_mtime_ns, stat.st_size)
    if problem:
        raise SpecError(where, f"the {what} '{rel}' cannot be read: {problem}", "check that it opens in a mesh viewer, or export it again")


@functools.lru_cache(maxsize=256)
def _mesh_problem(real: Path, mtime_ns: int, size: int) -> str:
    """Why the runtime cannot read the mesh at ``real`` ('' if it can); one read per file version."""
    from ejsrl.world.mesh import MeshFormatError, load_mesh

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # skipped VRML nodes are the runtime's to report
            load_mesh(real)
    except MeshFormatError as exc:
        return _reason(str(exc), real)
    except (OSError, ValueError, MemoryError) as exc:
        return str(exc) or type(exc).__name__
    return ""


def _reason(message: str, real: Path) -> str:
    """The loader's message without its leading path (``path:`` or ``path:LINE:COL:``)."""
    prefix = f"{real}:"
    if not message.startswith(prefix):
        return message
    rest = message[len(prefix):]
    head, sep, tail = rest.partition(": ")
    parts = head.split(":")
    if sep and len(parts) == 2 and all(x.isdigit() for x in parts):
        return f"line {parts[0]}, column {parts[1]}: {tail}"
    return rest.strip()


# -- asset names in spec code ------------------------------------------------------------------------
#: the function of a generated app that gives an asset's path (``asset = app_assets(__file__)``)
ASSET_FUNCTION = "asset"
_READ_MODES = frozenset("rbt")


def asset_names(listed: list[str]) -> frozenset[str]:
    """The strings that name the listed assets in code: each as listed and normalised (``./a.csv`` -> ``a.csv``)."""
    out: set[str] = set()
    for rel in listed:
        out.add(rel)
        out.add(PurePosixPath(rel.replace("\\", "/")).as_posix())
    return frozenset(out)


def asset_call(node: ast.Constant) -> ast.Call:
    """``asset('name')`` in place of the string constant ``node``; marked so that the author's
    text keeps its layout (``ejsgen._resolve.rewrite_source`` puts the call around the string)."""
    call = ast.Call(func=ast.Name(id=ASSET_FUNCTION, ctx=ast.Load()), args=[node], keywords=[])
    call._ejs_wrap = (f"{ASSET_FUNCTION}(", ")")  # type: ignore[attr-defined]
    return ast.copy_location(call, node)


def opens_an_asset(call: ast.Call, assets: frozenset[str]) -> bool:
    """Whether ``call`` is ``open(<asset>)`` for reading: its file a listed asset's path (or
    ``asset(...)``), its mode, if any, a constant made of ``r``, ``b`` and ``t``."""
    if not call.args:
        return False
    first = call.args[0]
    named = isinstance(first, ast.Constant) and first.value in assets
    computed = isinstance(first, ast.Call) and isinstance(first.func, ast.Name) and first.func.id == ASSET_FUNCTION
    if not (named or computed):
        return False
    modes = [a for a in call.args[1:2]] + [k.value for k in call.keywords if k.arg == "mode"]
    return all(isinstance(m, ast.Constant) and isinstance(m.value, str) and m.value and set(m.value) <= _READ_MODES for m in modes)


def _looks_like_path(text: str) -> bool:
    """Whether a string could be a relative file path (``data.csv``, ``img/a.png``), to look for beside the spec."""
    if not text or len(text) > 255 or "\n" in text or text.strip() != text:
        return False
    p = PurePosixPath(text.replace("\\", "/"))
    return not p.is_absolute() and ".." not in p.parts and bool(p.suffix) and not Path(text).is_absolute()


def unlisted_file(call: ast.Call, assets: frozenset[str], spec_dir: Path | None, *, asset_is_ours: bool) -> tuple[ast.AST, str, str] | None:
    """A file a call names that the built app will not have: ``(node, message, hint)`` or None.

    ``asset('x')`` (``asset_is_ours``: the name is the app's function, not the spec's own)
    of a path not listed under ``assets:``; or any call whose first argument is the path of
    a file beside the spec that is not listed (``np.loadtxt('data.csv')`` with no ``assets:``),
    which would read the working directory's file, not the app's.
    """
    if not call.args:
        return None
    first = call.args[0]
    if not (isinstance(first, ast.Constant) and isinstance(first.value, str)) or first.value in assets:
        return None
    text = first.value
    if asset_is_ours and isinstance(call.func, ast.Name) and call.func.id == ASSET_FUNCTION:
        from ejsgen._suggest import did_you_mean

        return first, f"'{text}' is not listed under 'assets:'", did_you_mean(text, sorted(assets)) or f"list the file: assets: [{text}]"
    if spec_dir is None or not _looks_like_path(text):
        return None
    try:
        folder = spec_dir.resolve()
        real = (folder / text).resolve()
        beside = real.is_file() and real.is_relative_to(folder)
    except (OSError, ValueError, RuntimeError):
        return None
    if not beside:
        return None
    return (first, f"'{text}' is a file beside the spec, but it is not listed under 'assets:', so the built app would not have it",
            f"list it: assets: [{text}]")
