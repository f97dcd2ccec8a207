"""Compile the spec's ``fmus:`` section: check each FMU and write the model's FMU methods.

Each FMU is checked when the spec is built, every error at the spec line that causes it:
the file is an FMU (an ``.fmu`` archive, or a folder holding an unpacked one), it offers
the requested kind (co-simulation or model exchange), every variable the spec names
exists with the right causality (inputs are inputs, outputs outputs, parameters
parameters), the output targets are model variables, and the FMU has a binary for this
platform. An FMU that ships its C sources instead (``sources/``, as FMI allows) is
compiled here with the system's C compiler and FMPy's FMI headers, so a lab can keep its
FMU as source; the result is cached by the sources' hash.

The model gets methods that read the inputs and parameters (the spec's expressions,
rewritten like all spec code) and write the outputs, and ``_fmus()`` declaring the FMUs
for the runtime (``ejsrl.fmi``).
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path, PurePosixPath
from typing import TYPE_CHECKING, Any

from ejsgen._assets import checked_asset, real_path_inside
from ejsgen._suggest import did_you_mean
from ejsgen.errors import Location, SpecError
from ejsgen.plan import Line

if TYPE_CHECKING:
    from ejsgen.compiler import Compiler
    from ejsgen.spec import Fmu

__all__ = ["compile_fmus", "prepare_fmu", "FmuFile", "cache_dir"]

#: the FMI types whose values the runtime exchanges
_TYPES = {"Real", "Integer", "Boolean", "String", "Binary", "Enumeration", "Float64", "Float32", "Int8", "UInt8", "Int16", "UInt16", "Int32", "UInt32", "Int64", "UInt64"}


class FmuFile:
    """A checked FMU: ``path`` the ``.fmu`` to copy into the app, ``rel`` its name there, ``md`` its description."""

    def __init__(self, path: Path, rel: str, md: Any) -> None:
        self.path = path
        self.rel = rel
        self.md = md
        self.vars = {v.name: v for v in md.modelVariables}


def cache_dir() -> Path:
    """Where FMUs compiled from sources are kept (``$EJSGEN_CACHE`` or ``~/.cache/ejsgen``)."""
    base = os.environ.get("EJSGEN_CACHE") or os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "ejsgen")
    return Path(base) / "fmu"


# -- the file ----------------------------------------------------------------------------------


def _inside(spec_dir: Path, rel: str, where: Location) -> Path:
    """The real path of the FMU folder ``rel``, refused if it leaves the spec's folder."""
    return real_path_inside(spec_dir, rel, where, "FMU", "copy the FMU")[1]


def _platform_dirs(fmpy: Any, version: str) -> str:
    return fmpy.platform_tuple if version.startswith("3") else fmpy.platform


def prepare_fmu(spec_dir: Path, rel: str, where: Location) -> FmuFile:
    """Check the FMU named ``rel`` and give the ``.fmu`` to ship (compiled from its sources if it has no binary here)."""
    try:
        import fmpy
    except ImportError:
        raise SpecError(where, "FMUs need FMPy, which is not installed", "pip install 'ejsgen[fmu]' (or pip install fmpy)") from None
    if (spec_dir / rel).is_dir():  # an unpacked FMU: checked here, file by file
        real = _inside(spec_dir, rel, where)
    else:  # an .fmu file: checked as every asset is (inside the spec's folder, no link out of it)

        _, real = checked_asset(spec_dir, rel, where, "FMU")
    if real.is_dir():
        for f in real.rglob("*"):
            if f.is_symlink():
                raise SpecError(where, f"the FMU folder '{rel}' holds a link ({f.relative_to(real).as_posix()})", "replace the link with the file itself")
        if not (real / "modelDescription.xml").is_file():
            raise SpecError(where, f"the folder '{rel}' is not an unpacked FMU (it has no modelDescription.xml)", "name an .fmu file, or the folder an FMU was unpacked into")
        out_rel = PurePosixPath(rel.replace("\\", "/")).as_posix().rstrip("/") + ".fmu"
    else:
        if not zipfile.is_zipfile(real):
            raise SpecError(where, f"'{rel}' is not an FMU (an FMU is a ZIP archive with a modelDescription.xml)", "export the model as an FMU (FMI 2.0 or 3.0)")
        with zipfile.ZipFile(real) as zf:
            if "modelDescription.xml" not in zf.namelist():
                raise SpecError(where, f"'{rel}' is not an FMU: it has no modelDescription.xml", "export the model as an FMU (FMI 2.0 or 3.0)")
        out_rel = PurePosixPath(rel.replace("\\", "/")).as_posix()
    try:
        md = fmpy.read_model_description(str(real), validate=True)
    except Exception as exc:  # noqa: BLE001 - FMPy raises plain exceptions with the XML's problems
        text = " ".join(str(exc).split())
        raise SpecError(where, f"the FMU '{rel}' has an invalid modelDescription.xml: {text[:400]}", "export the FMU again; FMPy's validation names the problem") from None
    if md.fmiVersion not in ("2.0",) and not md.fmiVersion.startswith("3."):
        raise SpecError(where, f"the FMU '{rel}' is FMI {md.fmiVersion}; ejsgen runs FMI 2.0 and 3.0 FMUs", "export it as FMI 2.0 or 3.0")
    ids = {i.modelIdentifier for i in (md.coSimulation, md.modelExchange) if i is not None}
    binary_dir = _platform_dirs(fmpy, md.fmiVersion)
    names = _names(real)
    missing = [i for i in sorted(ids) if f"binaries/{binary_dir}/{i}{fmpy.sharedLibraryExtension}" not in names]
    if not missing:
        return FmuFile(real, out_rel, md)
    if not md.buildConfigurations:
        have = sorted({n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") >= 2})
        raise SpecError(
            where,
            f"the FMU '{rel}' has no binary for this platform ({binary_dir})" + (f"; it has binaries for {', '.join(have)}" if have else "") + ", and no C sources to build one from",
            f"export the FMU for {binary_dir} (or with its C sources, which ejsgen compiles)",
        )
    return FmuFile(_compiled(real, rel, md, where), out_rel, md)


def _names(real: Path) -> set[str]:
    if real.is_dir():
        return {p.relative_to(real).as_posix() for p in real.rglob("*") if p.is_file()}
    with zipfile.ZipFile(real) as zf:
        return set(zf.namelist())


def _digest(real: Path) -> str:
    import fmpy

    h = hashlib.sha256(f"{fmpy.__version__}|{sys.platform}|{os.environ.get('CC', 'cc')}".encode())
    if real.is_dir():
        for p in sorted(real.rglob("*")):
            if p.is_file() and "binaries" not in p.relative_to(real).parts[:1]:
                h.update(p.relative_to(real).as_posix().encode() + b"\0" + p.read_bytes() + b"\0")
    else:
        h.update(real.read_bytes())
    return h.hexdigest()[:20]


def _compiled(real: Path, rel: str, md: Any, where: Location) -> Path:
    """The ``.fmu`` with a binary for this platform compiled from the FMU's sources (cached)."""
    ident = (md.coSimulation or md.modelExchange).modelIdentifier
    target = cache_dir() / f"{ident}-{_digest(real)}.fmu"
    if target.is_file():
        return target
    with tempfile.TemporaryDirectory(prefix="ejsgen-fmu-") as tmp:
        unz = Path(tmp) / ident
        if real.is_dir():
            shutil.copytree(real, unz, ignore=shutil.ignore_patterns("binaries"))
        else:
            with zipfile.ZipFile(real) as zf:
                zf.extractall(unz)
        try:
            _build_binary(unz, md)
        except _BuildError as exc:
            raise SpecError(where, f"cannot compile the C sources of the FMU '{rel}': {exc}", "install a C compiler (e.g. apt-get install gcc), or export the FMU with a binary for this platform") from None
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
        except OSError:  # no writable cache (a read-only home): keep it with the system's temporary files
            target = Path(tempfile.gettempdir()) / "ejsgen-fmu" / target.name
            target.parent.mkdir(parents=True, exist_ok=True)
        part = target.with_name(f".{target.name}.{os.getpid()}")
        from fmpy.util import create_zip_archive

        create_zip_archive(str(part), str(unz))
        os.replace(part, target)
    return target


class _BuildError(Exception):
    """Compiling an FMU's sources failed (the text says why)."""


def _build_binary(unz: Path, md: Any) -> None:
    """Compile ``unz/sources`` into ``unz/binaries/<platform>/<id>.<ext>``: the system's C
    compiler with FMPy's FMI headers (FMPy's CMake build on Windows)."""
    import fmpy

    if fmpy.system == "windows":  # pragma: no cover - CMake picks Visual Studio there
        from fmpy.build import build_platform_binary

        try:
            build_platform_binary(str(unz.resolve()))
        except Exception as exc:  # noqa: BLE001
            raise _BuildError(str(exc)) from None
        return
    cfg = md.buildConfigurations[0]
    fileset = cfg.sourceFileSets[0]
    headers = Path(fmpy.__file__).resolve().parent / "c-code"
    src = unz / "sources"
    files = [str(src / f) for f in fileset.sourceFiles]
    defines = [f"-D{d.name}" + (f"={d.value}" if d.value is not None else "") for d in fileset.preprocessorDefinitions]
    includes = [f"-I{src / d}" for d in getattr(fileset, "includeDirectories", [])] + [f"-I{src}", f"-I{headers}"]
    binary_dir = unz / "binaries" / _platform_dirs(fmpy, md.fmiVersion)
    binary_dir.mkdir(parents=True, exist_ok=True)
    ids = sorted({i.modelIdentifier for i in (md.coSimulation, md.modelExchange) if i is not None})
    cc = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        raise _BuildError("no C compiler found (cc, gcc or clang)")
    for ident in ids:
        out = binary_dir / f"{ident}{fmpy.sharedLibraryExtension}"
        cmd = [cc, "-shared", "-fPIC", "-O2", "-fvisibility=default", *defines, *includes, *files, "-o", str(out), "-lm"]
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        if proc.returncode != 0:
            errors = [ln for ln in proc.stderr.splitlines() if "error" in ln.lower()] or proc.stderr.splitlines()
            raise _BuildError("; ".join(ln.strip() for ln in errors[:3]) or f"{cc} exited with {proc.returncode}")


# -- the spec entry ------------------------------------------------------------------------------

_ROLE = {"inputs": ("input",), "outputs": ("output",), "parameters": ("parameter", "structuralParameter")}
_ROLE_WORD = {"inputs": "an input", "outputs": "an output", "parameters": "a parameter"}


def _check_variable(c: Compiler, f: FmuFile, name: str, fname: str, var: str, role: str, where: Location) -> bool:
    v = f.vars.get(var)
    if v is None:
        hint = did_you_mean(var, f.vars) or f"its variables: {', '.join(list(f.vars)[:12])}"
        c.errors.append(SpecError(where, f"the FMU '{fname}' has no variable '{var}'", hint))
        return False
    if v.type == "Clock" or getattr(v, "clocks", None):
        what = "an FMI 3 clock" if v.type == "Clock" else "clocked (it changes only when a clock ticks)"
        c.errors.append(SpecError(where, f"'{var}' of the FMU '{fname}' is {what}: FMI 3 clocks are not supported (they need scheduled execution or co-simulation event mode)", "use the FMU's variables that no clock drives"))
        return False
    if v.type not in _TYPES:
        c.errors.append(SpecError(where, f"'{var}' of the FMU '{fname}' is of type {v.type}, which ejsgen does not exchange"))
        return False
    if role == "start":
        if v.causality in ("independent", "calculatedParameter") or v.variability == "constant" or v.initial == "calculated":
            c.errors.append(SpecError(where, f"'{var}' of the FMU '{fname}' takes no start value (it is {v.causality}, {v.initial or v.variability})", "give start values to states, inputs and parameters"))
            return False
        return True
    if v.causality not in _ROLE[role]:
        same = [n for n, w in f.vars.items() if w.causality in _ROLE[role]]
        c.errors.append(
            SpecError(where, f"'{var}' is {_article(v.causality)} of the FMU '{fname}', not {_ROLE_WORD[role]}", f"its {role}: {', '.join(same[:12]) or 'none'}")
        )
        return False
    return True


def _article(word: str) -> str:
    return ("an " if word[:1] in "aeiou" else "a ") + word


def _target(c: Compiler, text: str, where: Location) -> str | None:
    """The assignment target ``self.x`` / ``self.q[0]`` of an output's model variable."""
    try:
        node = ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        node = None
    base = node.value if isinstance(node, ast.Subscript) else node
    index_ok = not isinstance(node, ast.Subscript) or all(
        isinstance(e, ast.Constant) and isinstance(e.value, int) for e in (node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice])
    )
    if not isinstance(base, ast.Name) or not index_ok:
        c.errors.append(SpecError(where, f"an FMU output goes to a model variable or an element of one ('tau' or 'tau[0]'), not '{text}'"))
        return None
    if base.id not in c.var_decls:
        c.errors.append(SpecError(where, f"'{base.id}' is not a model variable", did_you_mean(base.id, c.var_decls) or f"declare it, e.g. '{base.id}: 0.0'"))
        return None
    if base.id in c.state_vars:
        c.errors.append(SpecError(where, f"'{base.id}' is a state of an ODE page; an FMU output cannot also be integrated", "write the output into another variable"))
        return None
    if isinstance(node, ast.Subscript) and c.var_types.get(base.id) not in ("array", "auto"):
        c.errors.append(SpecError(where, f"'{base.id}' is not an array, so '{text}' has no element to write"))
        return None
    if c.var_types.get(base.id) == "int":
        c.var_types[base.id] = "float"
    return "self." + ast.unparse(node)


def _ode_index(c: Compiler, fmu: Fmu, path: tuple[Any, ...]) -> int | None:
    """The evolution page integrating a model-exchange FMU: ``ode:`` or the first ODE page;
    -1 when the model has none (the FMU's own solver advances it after each step)."""
    from ejsgen.spec import OdePage

    pages = c.spec.model.evolution
    odes = [i for i, p in enumerate(pages) if isinstance(p, OdePage)]
    if fmu.ode is None:
        return odes[0] if odes else -1
    if isinstance(fmu.ode, int) and not isinstance(fmu.ode, bool):
        if fmu.ode in odes:
            return fmu.ode
        c.errors.append(SpecError(c.loc(path + ("ode",)), f"evolution page {fmu.ode} is not an ODE page", f"ODE pages: {', '.join(map(str, odes)) or 'none'}"))
        return None
    named = [i for i in odes if pages[i].name == fmu.ode]
    if named:
        return named[0]
    c.errors.append(SpecError(c.loc(path + ("ode",)), f"no ODE page is named '{fmu.ode}'", did_you_mean(str(fmu.ode), [pages[i].name for i in odes if pages[i].name]) or "name the page with 'name:'"))
    return None


def compile_fmus(c: Compiler) -> None:
    """Check every FMU of the spec and add the model's FMU methods and ``_fmus()``."""
    fmus = c.spec.fmus
    if not fmus:
        return
    decls: list[Line] = []
    for name, fmu in fmus.items():
        path: tuple[Any, ...] = ("fmus", name)
        key = c.doc.key_loc(path)
        if not name.isidentifier() or name.startswith("_"):
            c.errors.append(SpecError(key, f"an FMU's name must be a Python identifier not starting with '_', not '{name}'"))
            continue
        if c.independents == [] and "t" not in c.var_decls:
            c.errors.append(SpecError(key, "FMUs run in simulated time: the model needs an independent variable (an ODE page or a variable 't')"))
            continue
        try:
            f = prepare_fmu(c.spec_dir, fmu.file, c.loc(path + ("file",)))
        except SpecError as err:
            c.errors.append(err)
            continue
        c.assets[f.rel] = f.path
        decls.extend(_compile_one(c, name, fmu, f, path))
    if decls:
        lines = [Line("from ejsrl.fmi import FmuDef"), Line(""), Line("return ["), *decls, Line("]")]
        c.add_method(c.method_name("_fmus"), "self", "The spec's FMUs (fmus:), instantiated afresh at every reset.", lines)


def fmu_shape(f: FmuFile, fmu: Fmu, var: str) -> tuple[int, ...]:
    """The shape of FMU variable ``var``: () for a scalar, an FMI 3 array's dimensions (a
    dimension set by a structural parameter takes the spec's number for it, else its start)."""
    out = []
    for d in getattr(f.vars[var], "dimensions", None) or []:
        if d.start is not None:
            out.append(int(d.start))
        else:
            given = fmu.parameters.get(d.variable.name)
            out.append(int(given) if isinstance(given, (int, float)) and not isinstance(given, bool) else int(d.variable.start))
    return tuple(out)


def _shape_words(shape: tuple[int, ...]) -> str:
    return "a number" if not shape else f"an array of shape ({', '.join(map(str, shape))}{',' if len(shape) == 1 else ''})"


def _check_capabilities(c: Compiler, fmu: Fmu, f: FmuFile, kind: str, path: tuple[Any, ...]) -> bool:
    """Capability flags the spec needs: a communication step that may change needs
    ``canHandleVariableCommunicationStepSize``."""
    cs = f.md.coSimulation
    if kind == "co_simulation" and cs is not None and not getattr(cs, "canHandleVariableCommunicationStepSize", True) and isinstance(fmu.step, str):
        c.errors.append(
            SpecError(
                c.loc(path + ("step",)),
                f"the FMU '{fmu.file}' cannot take a communication step that changes (canHandleVariableCommunicationStepSize is false), and 'step' is an expression",
                "give 'step' a number",
            )
        )
        return False
    return True


def _compile_one(c: Compiler, name: str, fmu: Fmu, f: FmuFile, path: tuple[Any, ...]) -> list[Line]:
    md = f.md
    if md.coSimulation is None and md.modelExchange is None:
        c.errors.append(
            SpecError(
                c.loc(path + ("file",)),
                f"the FMU '{fmu.file}' has neither a co-simulation nor a model-exchange interface; FMI 3 scheduled execution, the only one it offers, is not supported",
                "export the model as a co-simulation or model-exchange FMU",
            )
        )
        return []
    kind = fmu.kind or ("co_simulation" if md.coSimulation is not None else "model_exchange")
    offered = {"co_simulation": md.coSimulation, "model_exchange": md.modelExchange}
    if offered[kind] is None:
        other = "model_exchange" if kind == "co_simulation" else "co_simulation"
        where = c.loc(path + ("kind",)) if fmu.kind else c.doc.key_loc(path)
        c.errors.append(SpecError(where, f"the FMU '{fmu.file}' has no {kind.replace('_', '-')} interface", f"use kind: {other}"))
        return []
    ok = True
    for role in ("inputs", "outputs", "parameters", "start"):
        for var in getattr(fmu, role):
            ok = _check_variable(c, f, name, fmu.file, var, role, c.doc.key_loc(path + (role, var))) and ok
    if fmu.step is not None and kind == "model_exchange":
        c.errors.append(SpecError(c.loc(path + ("step",)), "'step' is the communication step of a co-simulation FMU; a model-exchange FMU takes the steps of its ODE page", "remove 'step', or use kind: co_simulation"))
        ok = False
    if fmu.ode is not None and kind == "co_simulation":
        c.errors.append(SpecError(c.loc(path + ("ode",)), "'ode' names the ODE page integrating a model-exchange FMU; a co-simulation FMU steps itself", "remove 'ode', or use kind: model_exchange"))
        ok = False
    ok = _check_capabilities(c, fmu, f, kind, path) and ok
    if ok:
        ok = _check_shapes(c, fmu, f, path) and ok
    ode = _ode_index(c, fmu, path) if kind == "model_exchange" else None
    for key in ("method", "tolerance"):
        if key in fmu.model_fields_set and ode != -1:
            why = "a co-simulation FMU steps itself" if kind == "co_simulation" else "this FMU's states are integrated by an ODE page, with that page's method and tolerance"
            c.errors.append(SpecError(c.loc(path + (key,)), f"'{key}' sets the solver of a model-exchange FMU in a model without ODE pages; {why}", f"remove '{key}'"))
            ok = False
    targets = {var: _target(c, text, c.loc(path + ("outputs", var))) for var, text in fmu.outputs.items()}
    if not ok or (kind == "model_exchange" and ode is None) or None in targets.values():
        return []
    args = [f"{name!r}", f"{f.rel!r}", f"{kind!r}"]
    base = f"_fmu_{name}"
    if fmu.inputs:
        m = _values_method(c, f"{base}_inputs", "inputs", fmu.inputs, path, f"The inputs of FMU '{name}', in order ({', '.join(fmu.inputs)}).")
        args += [f"inputs={tuple(fmu.inputs)!r}", f"read_inputs=self.{m}"]
    if fmu.outputs:
        lines = _output_lines(c, targets, path)
        m = c.add_method(c.method_name(f"{base}_outputs"), "self, values", f"Write the outputs of FMU '{name}' into the model.", lines)
        args += [f"outputs={tuple(fmu.outputs)!r}", f"write_outputs=self.{m}"]
    if fmu.parameters:
        m = _values_method(c, f"{base}_parameters", "parameters", fmu.parameters, path, f"The parameters of FMU '{name}', in order ({', '.join(fmu.parameters)}).")
        tunable = tuple(p for p in fmu.parameters if f.vars[p].variability == "tunable")
        args += [f"parameters={tuple(fmu.parameters)!r}", f"read_parameters=self.{m}"] + ([f"tunable={tunable!r}"] if tunable else [])
    if fmu.start:
        args.append(f"start={dict(fmu.start)!r}")
    if fmu.step is not None:
        if isinstance(fmu.step, str):
            m = c.expr_method(path + ("step",), f"{base}_step", f"the communication step of FMU '{name}'", f"The communication step of FMU '{name}'.")
        else:
            if not fmu.step > 0:
                c.errors.append(SpecError(c.loc(path + ("step",)), f"the communication step must be positive, not {fmu.step}"))
                return []
            m = c.add_method(c.method_name(f"{base}_step"), "self", f"The communication step of FMU '{name}'.", [Line(f"return {float(fmu.step)!r}")])
        if m:
            args.append(f"step=self.{m}")
    if ode is not None and ode >= 0:
        args.append(f"ode={ode}")
    elif ode == -1:
        args += [f"method={fmu.method!r}", f"tolerance={float(fmu.tolerance)!r}"]
    args.append(f"where={c.where(path, key=True)!r}")
    return [Line("    FmuDef(")] + [Line(f"        {a},") for a in args] + [Line("    ),")]


def _check_shapes(c: Compiler, fmu: Fmu, f: FmuFile, path: tuple[Any, ...]) -> bool:
    """FMI 3 arrays against the spec: an output goes to a whole model variable of its shape; an
    input's or parameter's value, when its shape is certain, has the variable's shape."""
    from ejsgen._shapes import infer_shape

    ok = True
    for var, text in fmu.outputs.items():
        want = fmu_shape(f, fmu, var)
        if not want:
            continue
        node = _parse(text)
        where = c.loc(path + ("outputs", var))
        if not isinstance(node, ast.Name):
            c.errors.append(SpecError(where, f"'{var}' of the FMU '{fmu.file}' is {_shape_words(want)}: it goes to a whole model variable, not '{text}'"))
            ok = False
            continue
        have = c.var_shapes.get(node.id)
        if have is not None and have != want:
            example = "[" + ", ".join(["0.0"] * want[0]) + "]" if len(want) == 1 else f"{{expr: 'np.zeros({want})'}}"
            c.errors.append(SpecError(where, f"'{var}' of the FMU '{fmu.file}' is {_shape_words(want)}, and '{node.id}' is {_shape_words(have)}", f"declare it so, e.g. '{node.id}: {example}'"))
            ok = False
    for role in ("inputs", "parameters"):
        for var, value in getattr(fmu, role).items():
            want = fmu_shape(f, fmu, var)
            if isinstance(value, str):
                node = _parse(value)
                have = infer_shape(_selfed(node), c.var_shapes) if node is not None else None
            else:
                have = ()
            if have is not None and have != want:
                c.errors.append(SpecError(c.loc(path + (role, var)), f"'{var}' of the FMU '{fmu.file}' is {_shape_words(want)}, and its value here is {_shape_words(have)}"))
                ok = False
    return ok


def _parse(text: str) -> ast.AST | None:
    try:
        return ast.parse(text.strip(), mode="eval").body
    except SyntaxError:
        return None


def _selfed(node: ast.AST) -> ast.AST:
    """``node`` with the model's variable names read as ``self.name`` (as the rewriter does)."""

    class _Self(ast.NodeTransformer):
        def visit_Name(self, n: ast.Name) -> ast.AST:
            return ast.Attribute(value=ast.Name("self", ast.Load()), attr=n.id, ctx=ast.Load())

    return _Self().visit(ast.parse(ast.unparse(node), mode="eval").body)


def _output_lines(c: Compiler, targets: dict[str, str | None], path: tuple[Any, ...]) -> list[Line]:
    """The assignments of the outputs: ``self.x = values[k]``, and outputs going to
    consecutive elements of one array as one slice (``self.tau[0:3] = values[0:3]``: one
    assignment instead of three, at every evaluation of a model-exchange FMU)."""
    import re

    element = re.compile(r"^(self\.[A-Za-z_][A-Za-z_0-9]*)\[(\d+)\]$")
    items = list(targets.items())
    lines: list[Line] = []
    k = 0
    while k < len(items):
        var, target = items[k]
        m = element.match(target or "")
        end = k + 1
        if m:
            while end < len(items):
                m2 = element.match(items[end][1] or "")
                if not (m2 and m2.group(1) == m.group(1) and int(m2.group(2)) == int(m.group(2)) + end - k):
                    break
                end += 1
        if end - k > 1 and m:
            first = int(m.group(2))
            names = ", ".join(v for v, _ in items[k:end])
            lines.append(Line(f"{m.group(1)}[{first}:{first + end - k}] = values[{k}:{end}]  # {names}", c.loc(path + ("outputs", var))))
        else:
            lines.append(Line(f"{target} = values[{k}]  # {var}", c.loc(path + ("outputs", var))))
        k = end
    return lines


def _values_method(c: Compiler, base: str, role: str, values: dict[str, Any], path: tuple[Any, ...], doc: str) -> str:
    lines = [Line("return (")]
    for var, value in values.items():
        vpath = path + (role, var)
        if isinstance(value, str):
            res = c.expr_source(vpath, f"the {role[:-1]} '{var}' of an FMU")
            if res is None:
                continue
            src = res[0].replace("\n", " ")
        else:
            src = repr(value)
        lines.append(Line(f"    {src},  # {var}", c.loc(vpath)))
    lines.append(Line(")"))
    return c.add_method(c.method_name(base), "self", doc, lines)
