"""Render an ``AppPlan`` into an app folder (and optionally a single-file ``.pyz``).

The templates only lay out what the plan decided. After rendering, the location markers
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
from ejsrl.sim.names import MATH_NAMES

from ejsgen import __version__
from ejsgen.errors import EjsError
from ejsgen.plan import AppPlan

__all__ = ["render_app", "write_app", "REQUIREMENTS", "runtime_dir"]

REQUIREMENTS = ["numpy>=1.26", "scipy>=1.11", "viser>=1.1,<1.2", "trimesh>=4.0", "opencv-python-headless>=4.8"]
_MARK = "  #@@ejsloc:"
_MARK_RE = re.compile(r"  #@@ejsloc:(\d+)$")
#: the prelude's math names, as the template imports them (from the runtime's list)
_MATH = textwrap.fill(", ".join(sorted(MATH_NAMES)), width=90, subsequent_indent="    ")


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


def _doc_lines(doc: str) -> list[str]:
    doc = doc.replace('"""', "'''").replace("\\", "\\\\").strip()
    lines = doc.splitlines() or [""]
    if len(lines) == 1:
        return [f'"""{lines[0]}"""']
    return [f'"""{lines[0]}'] + [ln.rstrip() for ln in lines[1:]] + ['"""']


def _wrap_dict(name: str, items: list[str], width: int = 96) -> str:
    if not items:
        return f"{name} = {{}}"
    lines = [f"{name} = {{"]
    cur = "   "
    for it in items:
        if len(cur) + len(it) + 2 > width:
            lines.append(cur.rstrip())
            cur = "   "
        cur += f" {it},"
    lines.append(cur.rstrip())
    lines.append("}")
    return "\n".join(lines)


def render_app(plan: AppPlan) -> str:
    """The text of ``app.py`` for a plan."""
    locs = []
    methods = []
    for m in plan.methods:
        body = []
        for line in m.lines:
            if line.where is not None and line.text.strip() and not line.text.lstrip().startswith("#"):
                body.append(f"{line.text}{_MARK}{len(locs)}")
                locs.append((line.where.line, line.where.col))
            else:
                body.append(line.text)
        methods.append({"name": m.name, "params": m.params, "doc_lines": _doc_lines(m.doc), "body": body, "comment": m.comment})
    variables = "{" + ", ".join(f"{k!r}: {v!r}" for k, v in plan.variables.items()) + "}"
    sim = ", ".join(f"{k}={v!r}" for k, v in plan.sim.items())
    text = _env().get_template("app.py.j2").render(
        version=__version__,
        title=plan.title.replace('"""', "'''"),
        title_repr=repr(plan.title),
        spec_name=plan.spec_name,
        spec_name_repr=repr(plan.spec_name),
        description_repr=repr(plan.description),
        author_repr=repr(plan.author),
        math_names=_MATH,
        user_imports=plan.user_imports,
        variables=variables,
        independent=repr(plan.independent),
        methods=methods,
        view_lines=plan.view_lines,
        after_class=plan.after_class,
        runtime_imports=plan.runtime_imports,
        sim=sim,
        spec_lines="@@SPEC_LINES@@",
    )
    out_lines = []
    table = []
    for lineno, line in enumerate(text.split("\n"), start=1):
        m = _MARK_RE.search(line)
        if m:
            spec_line, spec_col = locs[int(m.group(1))]
            table.append(f"{lineno}: ({spec_line}, {spec_col})")
            line = line[: m.start()]
        out_lines.append(line)
    text = "\n".join(out_lines)
    return text.replace("@@SPEC_LINES@@", _wrap_dict("Model.SPEC_LINES", table))


def _check_compiles(text: str, name: str) -> None:
    try:
        compile(text, name, "exec")
    except SyntaxError as exc:  # a generator bug, not the user's
        raise EjsError(f"internal error: the generated {name} does not compile ({exc.msg} at line {exc.lineno}); please report it") from None


def write_app(plan: AppPlan, out_dir: Path, *, bundle: bool = False) -> list[Path]:
    """Write the app folder ``out_dir`` (replacing it whole); returns the files written."""
    app_text = render_app(plan)
    _check_compiles(app_text, "app.py")
    env = _env()
    bundle_name = f"{out_dir.name}.pyz" if bundle else ""
    readme = env.get_template("README.md.j2").render(title=plan.title, description=plan.description, version=__version__, spec_name=plan.spec_name, bundle=bundle_name)
    urdf = ["yourdfpy>=0.0.56"] if "urdf" in app_text else []  # ejsrl.robotics.load_urdf, models.ur5_urdf
    reqs = env.get_template("requirements.txt.j2").render(requirements=REQUIREMENTS + urdf)
    if "from ejsrl.fmi import" in app_text:  # the spec's fmus: run through FMPy
        reqs += "fmpy>=0.3.20\n"
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
    main_text = _env().get_template("bundle_main.py.j2").render(title=plan.title, version=__version__, assets=repr([rel for _, rel in plan.assets]))
    _check_compiles(main_text, "__main__.py")
    with tempfile.TemporaryDirectory() as staging:
        stage = Path(staging)
        shutil.copy2(folder / "app.py", stage / "app.py")
        (stage / "__main__.py").write_text(main_text, encoding="utf-8")
        shutil.copytree(folder / "ejsrl", stage / "ejsrl")
        for _, rel in plan.assets:
            (stage / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(folder / rel, stage / rel)
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
