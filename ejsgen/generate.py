"""Render an ``AppPlan`` into an app folder (and optionally a single-file ``.pyz``).

``ejsgen.emit`` turns the plan's data into lines; the template only lays them out. After rendering, the location markers
on each line of model code are turned into ``Model.SPEC_LINES`` (app.py line -> spec
line and column), every Python file is compiled as a check, and the folder is written
next to its final place and moved there in one step, so a failed build leaves nothing
half-written.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import tempfile
import textwrap
import zipapp
from pathlib import Path

import jinja2
from ejsrl.sim.model import ModelBase
from ejsrl.sim.names import MATH_NAMES

from ejsgen import __version__
from ejsgen._assets import ASSET_FUNCTION
from ejsgen.errors import EjsError, SpecError
from ejsgen.emit import WIDTH, call_lines, flat, meta_call, method_lines, program_call, runtime_defaults, sim_call, used_names, view_lines
from ejsgen.plan import AppPlan, Line

__all__ = ["render_app", "write_app", "REQUIREMENTS", "OPENCV", "SERVE_ONLY", "runtime_dir"]

#: what every lab needs (viser serves it; trimesh makes its 3D shapes)
REQUIREMENTS = ["numpy>=1.26", "scipy>=1.11", "viser>=1.1,<1.2", "trimesh>=4.0"]
#: what only a lab that uses OpenCV needs (``AppPlan.uses_opencv``: cameras' images, vision functions, image files)
OPENCV = "opencv-python-headless>=4.8"
#: what only serving a lab imports: ``--headless``, ``--sweep`` and ``--help`` run without them (``ejsrl._needs``)
SERVE_ONLY = ["viser"]
_MARK = "  #@@ejsloc:"
_MARK_RE = re.compile(r"  #@@ejsloc:(\d+)$")
_TABLE = "@@SPEC_LINES@@"  # where the class's SPEC_LINES go, once the lines below are numbered


def runtime_dir() -> Path:
    """The ``ejsrl`` package folder to ship with apps."""
    import ejsrl

    return Path(ejsrl.__file__).resolve().parent


def _templates_dir() -> Path:
    import ejsgen.templates

    return Path(ejsgen.templates.__file__).resolve().parent


def _env() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(_templates_dir()),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )


#: where the runtime names a generated app may use come from (imported only when used)
_RUNTIME_FROM = {
    "ejsrl.app": ("AppMeta", "SimConfig", "app_assets", "main"),
    "ejsrl.sim": ("CodePage", "EventDef", "ModelBase", "OdePage"),
    "ejsrl.sim.programs": ("ProgramDef",),
}


def _imports(texts: list[str]) -> list[str]:
    """The runtime imports of the names the app's text uses."""
    used = used_names(texts)
    out = [f"from {mod} import {', '.join(n for n in names if n in used)}" for mod, names in _RUNTIME_FROM.items() if used & set(names)]
    if "E" in used:
        out.insert(2 if len(out) > 1 else len(out), "from ejsrl.view import elements as E")
    return out


def _code_names(lines: list[str]) -> set[str]:
    """The names a Python source line may load (not attributes, strings or comments; the
    values of an f-string, which Python 3.11 reads as one string token, are code)."""
    import ast
    import io
    import tokenize

    names: set[str] = set()
    for line in lines:
        previous = ""
        try:
            for tok in tokenize.generate_tokens(io.StringIO(line.strip() + "\n").readline):
                if tok.type == tokenize.NAME and previous != ".":
                    names.add(tok.string)
                elif tok.type == tokenize.STRING and "f" in re.match(r"[A-Za-z]*", tok.string).group().lower():
                    try:  # a label's f'... {2*pi/self.omega:.4f} ...': pi is loaded
                        names.update(n.id for n in ast.walk(ast.parse(tok.string, mode="eval")) if isinstance(n, ast.Name))
                    except SyntaxError:
                        pass
                previous = tok.string
        except (tokenize.TokenError, SyntaxError):  # a line of a longer statement: its start was read
            pass
    return names


def _prelude_imports(texts: list[str]) -> tuple[list[str], bool]:
    """The import of the prelude's math names the app's text uses, and whether it uses ``np``.

    Each line is read by Python's tokenizer on its own, names after a ``.`` (attributes) and
    inside strings and comments left out; a line inside a multi-line string reads as code, so
    a name may be imported that is not used (harmless), never the other way round.
    """
    words = _code_names(texts)
    names = sorted(set(MATH_NAMES) & words)
    out = textwrap.wrap(f"from math import {', '.join(names)}", width=WIDTH, subsequent_indent=" " * 17) if names else []
    if len(out) > 1:
        out = textwrap.wrap(f"from math import ({', '.join(names)})", width=WIDTH, subsequent_indent=" " * 18)
    return out, "np" in words


def _marked(lines: list[Line], locs: list[tuple[int, int]]) -> list[str]:
    """Lines as text, those with a spec location marked for the SPEC_LINES table."""
    out = []
    for line in lines:
        if line.where is not None and line.text.strip() and not line.text.lstrip().startswith("#"):
            out.append(f"{line.text}{_MARK}{len(locs)}")
            locs.append((line.where.line, line.where.col))
        else:
            out.append(line.text)
    return out


def _line_table(table: list[tuple[int, int, int]]) -> list[str]:
    """``SPEC_LINES`` in runs (consecutive app lines on consecutive spec lines, same column), as
    the class attribute's lines: the compact text that ``ModelBase`` turns into the table."""
    runs: list[list[int]] = []
    for app, line, col in table:
        last = runs[-1] if runs else None
        if last is not None and app == last[1] + 1 and line == last[2] + (last[1] - last[0]) + 1 and col == last[3]:
            last[1] = app
        else:
            runs.append([app, app, line, col])
    if not runs:
        return []
    text = " ".join(f"{a}={ln}:{c}" if a == b else f"{a}-{b}={ln}:{c}" for a, b, ln, c in runs)
    note = "  # app.py line=spec line:column, for errors"
    one = f'    SPEC_LINES = "{text}"'
    if len(one) <= WIDTH:
        return [one + note if len(one + note) <= WIDTH else one]
    chunks = textwrap.wrap(text, width=WIDTH - 11)  # 8 spaces, the quotes and the space that joins two
    return [f"    SPEC_LINES = ({note}", *[f'        "{c} "' for c in chunks[:-1]], f'        "{chunks[-1]}"', "    )"]


def _with_line_table(text: str, locs: list[tuple[int, int]]) -> str:
    """``text`` with its location marks taken off and the ``SPEC_LINES`` placeholder (in the class,
    above every marked line) replaced by the table of the marked lines.

    The table's own lines move the lines below it; the number of lines it takes grows with the
    line numbers it holds, so it is laid out again until that number stays the same.
    """
    lines = text.split("\n")
    at = lines.index(_TABLE)
    table = []
    for lineno, line in enumerate(lines, start=1):
        m = _MARK_RE.search(line)
        if m:
            if lineno <= at:
                raise EjsError(f"internal error: app.py line {lineno} is marked above SPEC_LINES; please report it")
            table.append((lineno, *locs[int(m.group(1))]))
            lines[lineno - 1] = line[: m.start()]
    size, rows = 1, _line_table(table)
    while rows and len(rows) != size:  # ends: more lines above only ever lengthen the table
        size = len(rows)
        rows = _line_table([(n + size - 1, ln, col) for n, ln, col in table])
    lines[at : at + 1] = rows
    return "\n".join(lines)


def render_app(plan: AppPlan) -> str:
    """The text of ``app.py`` for a plan."""
    locs: list[tuple[int, int]] = []
    methods = [_marked(method_lines(m), locs) for m in plan.methods]
    class_lines = _dict_lines("VARIABLES", plan.variables, 4)
    if plan.independent != ModelBase.INDEPENDENT:
        class_lines.append(f"    INDEPENDENT = {plan.independent!r}")
    class_lines.append(_TABLE)
    blocks: list[list[str]] = []
    if plan.programs:
        blocks.append(["Model.PROGRAMS = {", *(f"    {p.name!r}: {flat(program_call(p))}," for p in plan.programs), "}"])
    if plan.after_class:
        blocks.append(list(plan.after_class))
    blocks.append(_marked(view_lines(plan.view), locs))
    assets = _asset_block([ln for m in methods for ln in m] + [ln for b in blocks for ln in b])
    if assets:
        blocks.insert(0, assets)
    all_default = _default_sim(plan)
    sim = [] if all_default else [ln.text for ln in call_lines(sim_call(plan), 0, "SIMULATION = ", "")]
    blocks.append(sim + [ln.text for ln in call_lines(meta_call(plan), 0, "META = ", "")])
    texts = [ln for m in methods for ln in m] + [ln for b in blocks for ln in b] + ["ModelBase", "main", "AppMeta"]
    math_lines, uses_numpy = _prelude_imports(texts)
    text = _env().get_template("app.py.j2").render(
        header=_header(plan),
        prelude_imports=math_lines,
        numpy=uses_numpy,
        runtime_imports=_imports(texts) + list(plan.runtime_imports),
        user_imports=plan.user_imports,
        class_lines=class_lines,
        methods=methods,
        module_blocks=blocks,
        main_args="Model, VIEW, meta=META" if all_default else "Model, VIEW, sim=SIMULATION, meta=META",
        headless=plan.independent is not None,
    )
    return _with_line_table(text, locs)


def _asset_block(texts: list[str]) -> list[str]:
    """``asset = app_assets(__file__)`` when the app's code calls ``asset(...)`` (an asset
    named by its path in spec code, or ``asset(name)`` written there), else nothing."""
    if ASSET_FUNCTION not in _code_names(texts):
        return []
    return [
        "# asset('data.csv'): the path of a file the spec lists under assets, wherever the app runs",
        f"{ASSET_FUNCTION} = app_assets(__file__)",
    ]


def _default_sim(plan: AppPlan) -> bool:
    """Whether every run setting of the spec is the runtime's default (``SIMULATION`` is then left out)."""
    defaults = runtime_defaults("SimConfig")
    return all(k in defaults and v == defaults[k] for k, v in plan.sim.items())


def _header(plan: AppPlan) -> str:
    """The module docstring's first line(s): the title, where the file comes from."""
    title = plan.title.replace('"""', "'''").replace("\\", "\\\\")
    made = f"generated by ejsgen {__version__} from {plan.spec_name}; edit the spec and rebuild, not this file."
    one = f'"""{title}: {made}'
    return one if len(one) <= WIDTH else f'"""{title}:\n{made[0].upper()}{made[1:]}'


def _dict_lines(name: str, values: dict[str, str], indent: int) -> list[str]:
    """``NAME = {...}`` filled over lines of at most WIDTH columns."""
    items = [f"{k!r}: {v!r}" for k, v in values.items()]
    head = " " * indent + f"{name} = {{"
    return [ln.text for ln in _fill_items(head, items)]


def _fill_items(head: str, items: list[str]) -> list[Line]:
    lines, cur = [], head
    hang = " " * len(head)
    for i, it in enumerate(items):
        piece = it + (", " if i < len(items) - 1 else "")
        if cur != head and len(cur) + len(piece.rstrip()) > WIDTH:
            lines.append(Line(cur.rstrip()))
            cur = hang
        cur += piece
    lines.append(Line(cur + "}"))
    return lines


def _check_compiles(text: str, name: str) -> None:
    try:
        compile(text, name, "exec")
    except SyntaxError as exc:  # a generator bug, not the user's
        raise EjsError(f"internal error: the generated {name} does not compile ({exc.msg} at line {exc.lineno}); please report it") from None


def _check_urdf_parser(plan: AppPlan) -> None:
    """A spec that loads a URDF arm needs yourdfpy: say so at the build, at the spec line that
    loads it, as for FMPy, rather than serving an app whose scene stays empty."""
    import importlib.util

    try:  # found, not imported: importing it (trimesh, lxml) would double the build's time
        if importlib.util.find_spec("yourdfpy") is not None:
            return
    except (ImportError, ValueError):  # a broken or blocked installation counts as missing
        pass
    where = next((line.where for m in plan.methods for line in m.lines if "urdf" in line.text and line.where is not None), None)
    hint = "pip install yourdfpy (or pip install 'ejsgen[urdf]')"
    message = "URDF arms are read with yourdfpy, which is not installed"
    if where is None:
        raise EjsError(f"{plan.spec_name}: error: {message}; {hint}")
    raise SpecError(where, message, hint)


def write_app(plan: AppPlan, out_dir: Path, *, bundle: bool = False) -> list[Path]:
    """Write the app folder ``out_dir`` (replacing it whole); returns the files written."""
    app_text = render_app(plan)
    _check_compiles(app_text, "app.py")
    env = _env()
    bundle_name = f"{out_dir.name}.pyz" if bundle else ""
    fast = "susan" in app_text.lower()  # SUSAN corners (vision.susan_corners, a Pipeline's "susan"): numba compiles them
    readme = env.get_template("README.md.j2").render(title=plan.title, description=plan.description, version=__version__,
                                                     spec_name=plan.spec_name, bundle=bundle_name,
                                                     headless=plan.independent is not None, fast=fast)
    urdf = ["yourdfpy>=0.0.56"] if "urdf" in app_text else []  # ejsrl.robotics.load_urdf, models.ur5_urdf
    if urdf:
        _check_urdf_parser(plan)
    fmi = ["fmpy>=0.3.20"] if "from ejsrl.fmi import" in app_text else []  # the spec's fmus: run through FMPy
    plant = ["paho-mqtt>=2.0"] if "from ejsrl.app._plant_link import" in app_text else []  # the spec's plant: over MQTT
    opencv = [OPENCV] if plan.uses_opencv else []
    requirements = REQUIREMENTS + opencv + urdf + fmi + plant
    reqs = env.get_template("requirements.txt.j2").render(requirements=requirements, fast=fast)
    app_text += _script_metadata(requirements)  # at the end: app.py's line numbers stay
    out_dir = out_dir.resolve()
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{out_dir.name}.", dir=out_dir.parent))
    tmp.chmod(0o777 & ~_umask())  # mkdtemp makes it 0700; the app folder gets the mode of any new folder
    try:
        (tmp / "app.py").write_text(app_text, encoding="utf-8")
        (tmp / "README.md").write_text(readme, encoding="utf-8")
        (tmp / "requirements.txt").write_text(reqs, encoding="utf-8")
        shutil.copytree(runtime_dir(), tmp / "ejsrl", ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        for src, rel in plan.assets:
            dest = _asset_dest(tmp, src, rel)
            dest.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest, follow_symlinks=False)
        if bundle:
            _write_bundle(plan, tmp, tmp / bundle_name)
        _replace_dir(tmp, out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return sorted(p for p in out_dir.rglob("*") if p.is_file() and "__pycache__" not in p.parts)


def _script_metadata(requirements: list[str]) -> str:
    """Inline script metadata (PEP 723): ``uv run app.py`` and ``pipx run app.py`` install these
    (with the ``ejsrl`` folder beside app.py); ``[tool.ejsrl] serve-only`` names those that
    ``--headless``, ``--sweep`` and ``--help`` do not need (``ejsrl._needs`` reads both)."""
    deps = "".join(f'#     "{r}",\n' for r in requirements)
    serve_only = ", ".join(f'"{name}"' for name in SERVE_ONLY)
    return (
        "\n\n# The packages this app needs, as inline script metadata (PEP 723): `uv run app.py` or\n"
        "# `pipx run app.py` installs them and runs it (the ejsrl folder beside app.py is the runtime);\n"
        "# requirements.txt lists the same for pip.\n"
        f'# /// script\n# requires-python = ">=3.11"\n# dependencies = [\n{deps}# ]\n'
        f"# [tool.ejsrl]\n# serve-only = [{serve_only}]\n# ///\n"
    )


def _umask() -> int:
    """The process's umask (read by setting it and putting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _asset_dest(folder: Path, src: Path, rel: str) -> Path:
    """Where the asset ``src`` goes in ``folder``; refuses links and paths that leave the folder.

    The compiler has already resolved every asset to a real file inside the spec's folder;
    this is the last guard before anything is copied into an app or its ``.pyz``.
    """
    dest = folder / rel
    if Path(src).is_symlink() or not Path(src).is_file():
        raise EjsError(f"internal error: the asset '{rel}' ({src}) is not a regular file; please report it")
    if ".." in Path(rel).parts or Path(rel).is_absolute() or not dest.resolve().is_relative_to(folder.resolve()):
        raise EjsError(f"internal error: the asset '{rel}' would be written outside the app folder; please report it")
    return dest


def _write_bundle(plan: AppPlan, folder: Path, target: Path) -> None:
    from ejsrl.app._assets import MANIFEST, manifest_of

    main_text = _env().get_template("bundle_main.py.j2").render(title=plan.title, version=__version__)
    _check_compiles(main_text, "__main__.py")
    with tempfile.TemporaryDirectory() as staging:
        stage = Path(staging)
        shutil.copy2(folder / "app.py", stage / "app.py")
        (stage / "__main__.py").write_text(main_text, encoding="utf-8")
        shutil.copytree(folder / "ejsrl", stage / "ejsrl")
        for _, rel in plan.assets:
            (stage / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(folder / rel, stage / rel)
        # each asset's SHA-256 and size: the archive extracts them once, checked, into a per-user cache
        (stage / MANIFEST).write_bytes(manifest_of({rel: folder / rel for _, rel in plan.assets}))
        buf = io.BytesIO()
        zipapp.create_archive(stage, buf, interpreter="/usr/bin/env python3", compressed=True)
        target.write_bytes(buf.getvalue())
        target.chmod(0o755)


def _replace_dir(new: Path, final: Path) -> None:
    """Move ``new`` to ``final`` (an existing folder there is replaced)."""
    if final.exists():
        if not final.is_dir():
            raise EjsError(f"{final} exists and is not a folder")
        old = final.with_name(f".{final.name}.old")
        if old.exists():
            shutil.rmtree(old)
        final.rename(old)
        try:
            new.rename(final)
        except BaseException:
            old.rename(final)
            raise
        shutil.rmtree(old, ignore_errors=True)
    else:
        new.rename(final)
