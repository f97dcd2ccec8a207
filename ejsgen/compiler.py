"""Compile a validated spec into an ``AppPlan``: the model's methods, the view, the settings.

Every code block and expression is parsed with ``ast``, its names resolved by the
language's rules (``_resolve``), checked, and rewritten into a method of the generated
``Model`` class. Nothing from the spec is evaluated here or at run time as text.
"""

from __future__ import annotations

import ast
import importlib.util
from pathlib import Path
from typing import Any

from ejsgen._assets import ASSET_FUNCTION, asset_names
from ejsgen._resolve import Names, Snippet, assigned_names, parse_snippet, rewrite, rewrite_source, source_lines
from ejsgen._shapes import infer_shape, literal_shape
from ejsgen._suggest import did_you_mean, text_value_hint
from ejsgen.errors import Location, SpecError, SpecErrors
from ejsgen.emit import declare_method, list_lines, page_call
from ejsgen.plan import AppPlan, Call, EventPlan, Expr, Line, Method, OdePlan, ProgramPlan, Ref, Variable, body_lines, py
from ejsgen.spec import Code, CodeEvolutionPage, OdePage
from ejsgen.validate import CONTROL_NAMES, MATH_NAMES, PRELUDE_NAMES, Checked, free_name, import_name_clash, model_name_clash
from ejsgen.yamlload import Path_, TextOrigin

__all__ = ["compile_spec", "Compiler"]


class Compiler:
    """Builds the plan; collects every error before raising them together."""

    def __init__(self, checked: Checked, spec_path: Path) -> None:
        self.checked = checked
        self.doc = checked.doc
        self.spec = checked.spec
        self.spec_path = spec_path
        self.spec_dir = spec_path.parent
        self.errors: list[SpecError] = []
        self.methods: list[Method] = []
        self._method_names: set[str] = set()
        self.var_types: dict[str, str] = {}
        self.var_shapes: dict[str, tuple[int, ...] | None] = {}
        self.var_decls = {v.name: v for v in checked.variables}
        self.state_vars: set[str] = set()
        self.independents: list[str] = []
        self.assets: dict[str, Path] = {}
        self.after_class: list[str] = []
        self.runtime_imports: list[str] = []
        self.program_labels: list[Call] = []
        self.programs: list[ProgramPlan] = []
        self.var_plans: list[Variable] = []
        self.pages: list[OdePlan | Call] = []
        #: each ODE page's preliminary locals (by the page's path), which its rates see
        self.preliminary_locals: dict[Path_, set[str]] = {}
        self.names = Names(variables=set(self.var_decls), functions=set(), controls=set(CONTROL_NAMES), globals={"np", *MATH_NAMES})
        # assets named by their path in code become asset('...'); asset(name) finds any of them
        self.names.assets = asset_names(self.spec.assets)
        self.names.spec_dir = self.spec_dir
        self.names.globals.add(ASSET_FUNCTION)

    # -- helpers ----------------------------------------------------------------------------------
    def loc(self, path: Path_) -> Location:
        return self.doc.loc(path)

    def where(self, path: Path_, *, key: bool = False) -> str:
        """A location for the generated app: the spec's file name (not the build's path).

        ``key``: the location of the mapping key at ``path`` rather than of its value.
        """
        loc = self.doc.key_loc(path) if key else self.doc.loc(path)
        return f"{self.spec_path.name}:{loc.line}:{loc.col}"

    def snippet(self, path: Path_, what: str, mode: str = "exec", text: str | None = None) -> Snippet:
        origin = self.doc.origins.get(path)
        if origin is None:
            line, col = self.doc.positions.get(path, (1, 1))
            origin = TextOrigin(line, col, False)
        value = text if text is not None else _get(self.doc.data, path)
        return Snippet(str(value), origin, self.doc.file, what, mode)

    def method_name(self, base: str) -> str:
        name = base
        i = 2
        while name in self._method_names:
            name = f"{base}_{i}"
            i += 1
        self._method_names.add(name)
        return name

    def add_method(self, name: str, params: str, doc: str, lines: list[Line], comment: str = "") -> str:
        self.methods.append(Method(name, params, doc, lines or [Line("pass")], comment))
        self._method_names.add(name)
        return name

    def code_method(self, base: str, code: Code | None, path: Path_, what: str) -> str | Ref | None:
        """A method ``base`` (made unique) running the code at ``path``; a bare call of a custom
        function or control with no arguments (``kick()``) is that method itself (a ``Ref``)."""
        lines = self.code_lines(code, path, what)
        if isinstance(code, str):
            one = _single_call(self, path)
            if one is not None:
                return Ref(one)
        if not lines:
            return None
        return self.add_method(self.method_name(base), "self", "", lines)

    def parse(self, snippet: Snippet) -> ast.AST | None:
        """Parse a snippet; a syntax error is recorded (and None returned)."""
        try:
            return parse_snippet(snippet)
        except SpecError as err:
            self.errors.append(err)
            return None

    def parse_rewrite(self, snippet: Snippet, *, extra_locals: tuple[str, ...] = (), names: Names | None = None) -> ast.AST | None:
        tree = self.parse(snippet)
        if tree is None:
            return None
        new, errs = rewrite(tree, names or self.names, snippet, extra_locals=extra_locals)
        self.errors.extend(errs)
        return new

    # -- code blocks ---------------------------------------------------------------------------------
    def code_lines(self, code: Code | None, path: Path_, what: str, *, names: Names | None = None, extra_locals: tuple[str, ...] = ()) -> list[Line]:
        """The rewritten lines of a code block (a string or a list of pages); ``extra_locals``:
        names its pages may use as locals (assigned by another of its pages)."""
        if code is None:
            return []
        if isinstance(code, str):
            return self._block_lines(path, what, names, extra_locals)
        lines: list[Line] = []
        for i, page in enumerate(code):
            ppath = path + (i, "code")
            title = page.name or f"page {i + 1}"
            if not page.enabled:
                lines.append(Line(f"# {title}: disabled"))
                continue
            lines.append(Line(f"# {title}"))
            lines.extend(self._block_lines(ppath, f"{what} ({title})", names, extra_locals))
        return lines

    def _block_lines(self, path: Path_, what: str, names: Names | None = None, extra_locals: tuple[str, ...] = ()) -> list[Line]:
        snippet = self.snippet(path, what)
        tree = self.parse_rewrite(snippet, names=names, extra_locals=extra_locals)
        if tree is None or not isinstance(tree, ast.Module) or not tree.body:
            return []
        return self.tree_lines(snippet, tree)

    def tree_lines(self, snippet: Snippet, tree: ast.Module) -> list[Line]:
        """The lines of a rewritten block: the author's text (comments and line breaks kept),
        or the unparsed tree when the text cannot be kept."""
        text = rewrite_source(snippet, tree)
        if text is None:
            return body_lines(tree.body, lambda n: snippet.location(n.lineno, n.col_offset))
        lines = [Line(t, w) for t, w in source_lines(snippet, text)]
        while lines and not lines[-1].text.strip():
            lines.pop()
        while lines and not lines[0].text.strip():
            lines.pop(0)
        return lines

    def expr(self, path: Path_, what: str, *, text: str | None = None, lam: str | None = None, extra_locals: tuple[str, ...] = ()) -> Expr | None:
        """The rewritten expression at ``path`` as written by the author (``lam``: as a lambda;
        ``extra_locals``: locals of code that runs before it in the same method)."""
        snippet = self.snippet(path, what, "eval", text)
        tree = self.parse_rewrite(snippet, extra_locals=extra_locals)
        if tree is None:
            return None
        assert isinstance(tree, ast.Expression)
        source = rewrite_source(snippet, tree) or ast.unparse(tree.body)
        if lam is not None and "\n" in source:
            source = ast.unparse(tree.body)
        where = snippet.location(tree.body.lineno, tree.body.col_offset)
        return Expr(source, where, snippet.text.strip(), lam)

    def expr_method(self, path: Path_, base: str, what: str, doc: str, *, text: str | None = None) -> str | None:
        """Compile the expression at ``path`` into a method ``base(self)``; returns its name."""
        snippet = self.snippet(path, what, "eval", text)
        tree = self.parse_rewrite(snippet)
        if tree is None:
            return None
        assert isinstance(tree, ast.Expression)
        name = self.method_name(base)
        where = snippet.location(tree.body.lineno, tree.body.col_offset)
        self.add_method(name, "self", doc, [Line(f"return {ast.unparse(tree.body)}", where)])
        return name

    def expr_source(self, path: Path_, what: str, *, text: str | None = None) -> tuple[str, ast.expr] | None:
        """The rewritten source of the expression at ``path`` (for inlining into a method)."""
        snippet = self.snippet(path, what, "eval", text)
        tree = self.parse_rewrite(snippet)
        if tree is None:
            return None
        assert isinstance(tree, ast.Expression)
        return rewrite_source(snippet, tree) or ast.unparse(tree.body), tree.body

    def text_hint(self, expr: str) -> str:
        """For an expression that is only the name of a variable whose value is text (a
        quoted ``"np.zeros((22, 3))"``: shape ()), how to declare it as an expression; else ''."""
        name = expr.strip()
        for v in self.checked.variables:
            if v.name == name and v.decl.expr is None and isinstance(v.decl.value, str):
                return text_value_hint(name, v.decl.value)
        return ""

    # -- imports --------------------------------------------------------------------------------------
    def compile_imports(self) -> list[str]:
        lines = []
        for i, line in enumerate(self.spec.imports):
            path = ("imports", i)
            snippet = self.snippet(path, "imports")
            tree = self.parse(snippet)
            if tree is None:
                continue
            assert isinstance(tree, ast.Module)
            if len(tree.body) != 1 or not isinstance(tree.body[0], (ast.Import, ast.ImportFrom)):
                self.errors.append(SpecError(self.loc(path), "an 'imports' entry must be one import statement", "e.g. 'from ejsrl.robotics import models'"))
                continue
            stmt = tree.body[0]
            module = stmt.module if isinstance(stmt, ast.ImportFrom) else stmt.names[0].name
            if isinstance(stmt, ast.ImportFrom) and stmt.level:
                self.errors.append(SpecError(self.loc(path), "relative imports are not supported in specs"))
                continue
            try:
                found = importlib.util.find_spec(module or "")
            except (ModuleNotFoundError, ValueError):
                found = None
            if found is None:
                self.errors.append(SpecError(self.loc(path), f"cannot find the module '{module}'", "install it, or check the spelling"))
                continue
            for alias in stmt.names:
                if alias.name == "*":
                    self.errors.append(SpecError(self.loc(path), "'import *' hides which names exist; import names explicitly"))
                    continue
                bound = (alias.asname or alias.name).split(".")[0]
                clash = import_name_clash(bound, self.var_decls)
                if clash is not None:
                    self.errors.append(SpecError(snippet.location(alias.lineno, alias.col_offset), clash, _rename_import(stmt, alias, bound, self.var_decls)))
                self.names.globals.add(bound)
            lines.append(ast.unparse(stmt))
        return lines

    # -- variables ------------------------------------------------------------------------------------
    def compile_variables(self) -> None:
        declared: list[str] = []
        for v in self.checked.variables:
            decl = v.decl
            where = self.doc.key_loc(v.path)
            if decl.expr is not None:
                epath = v.path + ("expr",)
                res = self.expr_source(epath, f"the initial value of '{v.name}'")
                if res is not None:
                    src, node = res
                    later = {a.attr for a in ast.walk(node) if _is_self_attr(a) and a.attr in self.var_decls and a.attr not in declared}
                    for name in sorted(later):
                        self.errors.append(SpecError(self.loc(epath), f"'{v.name}' uses '{name}' before '{name}' is declared", "variables are initialised in declaration order"))
                    self._declared(v, src, where)
                self.var_types[v.name] = "auto"
                self.var_shapes[v.name] = None
            else:
                src, vtype, shape, err = _literal_source(decl.value)
                if err:
                    vpath = v.path + ("value",) if isinstance(_get(self.doc.data, v.path), dict) else v.path
                    self.errors.append(SpecError(self.loc(vpath), f"variable '{v.name}': {err}"))
                    continue
                self._declared(v, src, where)
                self.var_types[v.name] = vtype
                self.var_shapes[v.name] = shape
            declared.append(v.name)
        self.methods.append(declare_method(self.var_plans))

    def _declared(self, v: Any, src: str, where: Location) -> None:
        """The plan of a variable: its initial value (an expression as the author laid it out)."""
        first, *rest = src.split("\n")
        init = [Line(f"self.{v.name} = {first}", where)] + [Line(r, where) for r in rest]
        decl = v.decl
        self.var_plans.append(Variable(v.name, "", init, getattr(decl, "unit", None), getattr(decl, "doc", None)))

    # -- custom functions -------------------------------------------------------------------------------
    def collect_custom_names(self) -> list[tuple[ast.FunctionDef, Snippet, Path_]]:
        out = []
        code = self.spec.model.custom
        if code is None:
            return out
        pages = [(("model", "custom"), code)] if isinstance(code, str) else [
            (("model", "custom", i, "code"), p.code) for i, p in enumerate(code) if p.enabled
        ]
        for path, _ in pages:
            snippet = self.snippet(path, "model.custom")
            tree = self.parse(snippet)
            if tree is None:
                continue
            assert isinstance(tree, ast.Module)
            for stmt in tree.body:
                if not isinstance(stmt, ast.FunctionDef):
                    self.errors.append(SpecError(snippet.location(stmt.lineno, stmt.col_offset), "'custom' holds function definitions only (def name(...): ...)"))
                    continue
                loc = snippet.location(stmt.lineno, stmt.col_offset)
                if stmt.name in self.var_decls:
                    self.errors.append(SpecError(loc, f"the function '{stmt.name}' has the name of a variable"))
                elif (clash := model_name_clash(stmt.name, "custom function")) is not None:
                    self.errors.append(SpecError(loc, *clash))
                elif stmt.name in self.names.globals:
                    self.errors.append(SpecError(loc, f"the function '{stmt.name}' has the name of an import", f"rename the function (e.g. '{free_name(stmt.name, self.names.globals)}')"))
                elif stmt.name.startswith("_"):
                    self.errors.append(SpecError(loc, f"custom function names cannot start with '_' ('{stmt.name}')"))
                elif stmt.name in self.names.functions:
                    self.errors.append(SpecError(loc, f"the function '{stmt.name}' is defined twice"))
                self.names.functions.add(stmt.name)
                out.append((stmt, snippet, path))
        return out

    def compile_custom(self, defs: list[tuple[ast.FunctionDef, Snippet, Path_]]) -> None:
        for fn, snippet, _path in defs:
            new, errs = rewrite(ast.Module(body=[fn], type_ignores=[]), self.names, snippet)
            self.errors.extend(errs)
            assert isinstance(new, ast.Module)
            func = new.body[0]
            assert isinstance(func, ast.FunctionDef)
            own = None if func.decorator_list else _custom_source(snippet, func)
            if own is not None:
                self._method_names.add(func.name)
                self.methods.append(Method(func.name, "", "", own, raw=True))
                continue
            func.args.args.insert(0, ast.arg(arg="self"))
            doc = ast.get_docstring(func) or ""
            body = func.body[1:] if doc and func.body and isinstance(func.body[0], ast.Expr) else func.body
            where_of = lambda n, s=snippet: s.location(n.lineno, n.col_offset)  # noqa: E731
            lines = body_lines(body, where_of) if body else [Line("pass")]
            params = ast.unparse(func.args)
            self._method_names.add(func.name)
            for dec in func.decorator_list:
                lines.insert(0, Line(f"# decorator @{ast.unparse(dec)} is applied below"))
            self.add_method(func.name, params, doc, lines)

    # -- init, fixed relations --------------------------------------------------------------------------
    def compile_blocks(self) -> None:
        m = self.spec.model
        init = self.code_lines(m.init, ("model", "init"), "model.init")
        if init:
            self.add_method("_init", "self", "", init)
        fixed = self.code_lines(m.fixed_relations, ("model", "fixed_relations"), "model.fixed_relations")
        if fixed:
            self.add_method("_fixed_relations", "self", "", fixed)

    # -- evolution ----------------------------------------------------------------------------------------
    def collect_preliminary_locals(self) -> None:
        """The locals of each ODE page's ``preliminary`` (names it assigns that are not model
        variables): its page's rates see them (``self.preliminary_locals``, by the page's path);
        any other block that uses one is told where it is visible and how to share it."""
        for i, page in enumerate(self.spec.model.evolution):
            if not isinstance(page, OdePage) or page.ode.preliminary is None:
                continue
            path = ("model", "evolution", i, "ode")
            code = page.ode.preliminary
            texts = [(path + ("preliminary",), code)] if isinstance(code, str) else [
                (path + ("preliminary", j, "code"), p.code) for j, p in enumerate(code) if p.enabled
            ]
            found: set[str] = set()
            for ppath, text in texts:
                try:
                    tree = ast.parse(text)
                except SyntaxError:
                    continue  # reported where the block is compiled
                found |= assigned_names(tree.body) - set(self.var_decls) - self.names.functions
            self.preliminary_locals[path] = found
            title = page.name or f"page {i + 1}"
            loc = self.loc(path + ("preliminary",))
            for name in sorted(found):
                self.names.elsewhere.setdefault(name, (
                    f"it is a local of the preliminary code of the ODE page '{title}' (line {loc.line}), seen only by that page's rates",
                    f"to use it elsewhere, make it a model variable: declare '{name}: 0.0' under model.variables (the preliminary code then sets it for everyone)",
                ))

    def compile_evolution(self) -> None:
        evolution = self.spec.model.evolution
        first = len(self.methods)
        odes = sum(1 for p in evolution if isinstance(p, OdePage))
        for i, page in enumerate(evolution):
            path = ("model", "evolution", i)
            title = page.name or f"page {i + 1}"
            base = _slug(page.name) if page.name else f"page{i + 1}"
            if isinstance(page, CodeEvolutionPage):
                lines = self.code_lines(page.code, path + ("code",), f"evolution ({title})")
                name = self.add_method(self.method_name(f"_{base}"), "self", "", lines)
                self.pages.append(Call("CodePage", [title, Ref(name, "self")], {} if page.enabled else {"enabled": False}))
            else:
                assert isinstance(page, OdePage)
                ode = self.compile_ode(page, path + ("ode",), title, "" if odes == 1 and not page.name else base)
                if ode is not None:
                    self.pages.append(ode)
        if self.pages:
            items = [page_call(p) if isinstance(p, OdePlan) else p for p in self.pages]
            lines = list_lines("return ", items, 0)
            self.add_method("_evolution", "self", "", lines)
            self.methods.insert(first, self.methods.pop())  # read first, then the pages' parts

    def compile_ode(self, page: OdePage, path: Path_, title: str, base: str) -> OdePlan | None:
        ode = page.ode
        ind = ode.independent
        if ind not in self.var_decls:
            self.errors.append(SpecError(self.loc(path + ("independent",)) if "independent" in _get(self.doc.data, path) else self.loc(path), f"the independent variable '{ind}' is not a variable", did_you_mean(ind, self.var_decls) or f"declare it, e.g. '{ind}: 0.0'"))
            return None
        self.independents.append(ind)
        shared = tuple(sorted(self.preliminary_locals.get(path, ())))
        states: list[str] = []
        rates: dict[str, Expr] = {}
        for state, rate in ode.equations.items():
            spath = path + ("equations", state)
            if state not in self.var_decls:
                self.errors.append(SpecError(self.doc.key_loc(spath), f"the state '{state}' is not a variable", did_you_mean(state, self.var_decls)))
                continue
            if state == ind:
                self.errors.append(SpecError(self.doc.key_loc(spath), f"'{state}' is the independent variable and cannot also be a state"))
                continue
            if state in self.state_vars:
                self.errors.append(SpecError(self.doc.key_loc(spath), f"the state '{state}' is already integrated by another ODE page"))
                continue
            if self.var_types.get(state) in ("bool", "str"):
                self.errors.append(SpecError(self.doc.key_loc(spath), f"the state '{state}' must be a number or an array of numbers, not {self.var_types[state]}"))
                continue
            self.state_vars.add(state)
            states.append(state)
            if isinstance(rate, str):
                res = self.expr(spath, f"the rate of '{state}'", extra_locals=shared)
                if res is None:
                    continue
                shape = infer_shape(ast.parse(res.source.strip(), mode="eval").body if "\n" not in res.source else ast.parse(f"({res.source})", mode="eval").body, self.var_shapes)
            else:
                res, shape = Expr(repr(float(rate)), self.loc(spath)), ()
            want = self.var_shapes.get(state)
            if want is not None and shape is not None and shape != want and shape != ():
                self.errors.append(SpecError(self.loc(spath), f"the rate of '{state}' has shape {_shape_text(shape)} but '{state}' has shape {_shape_text(want)}"))
            if want == () and shape not in (None, ()):
                self.errors.append(SpecError(self.loc(spath), f"the rate of '{state}' is an array of shape {_shape_text(shape)} but '{state}' is a number"))
            rates[state] = Expr(res.source, self.loc(spath))
        if not states:
            if not ode.equations:
                self.errors.append(SpecError(self.loc(path), "an ode page needs at least one equation"))
            return None
        for s in states + [ind]:
            if self.var_types.get(s) == "int":
                self.var_types[s] = "float"
        prefix = f"_{base}_" if base else "_"
        # rates: one per state, in order
        listed = f"[{', '.join(r.source for r in rates.values())}]"
        rates_fn: Expr | str
        preliminary = None
        pre = self.code_lines(ode.preliminary, path + ("preliminary",), f"the preliminary code of {title}", extra_locals=shared) if ode.preliminary is not None else []
        rate_lines = [Line("return [")] + [Line(f"    {r.source},  # d{s}/d{ind}", r.where) for s, r in rates.items()] + [Line("]")]
        if shared and pre:  # the preliminary's locals are the rates': one method runs both
            head = Line(f"# preliminary: {', '.join(shared)} {'is a local' if len(shared) == 1 else 'are locals'} shared with the rates")
            rates_fn = self.add_method(self.method_name(f"{prefix}rates"), "self", "", [head, *pre, *rate_lines])
        else:
            if len(listed) <= 60 and all("\n" not in r.source for r in rates.values()):  # short: inline, next to its states
                rates_fn = Expr(listed, next(iter(rates.values())).where, "", "")
            else:
                rates_fn = self.add_method(self.method_name(f"{prefix}rates"), "self", "", rate_lines)
            if ode.preliminary is not None:
                preliminary = self.add_method(self.method_name(f"{prefix}preliminary"), "self", "", pre)
        # step
        step: Expr | float
        if "step" not in _get(self.doc.data, path):
            if "dt" not in self.var_decls:
                self.errors.append(SpecError(self.loc(path), "the default step 'dt' is not a variable", "declare 'dt' or give 'step:'"))
            step = Expr("self.dt", self.loc(path), "dt", "")
        elif isinstance(ode.step, str):
            step = self.expr(path + ("step",), f"the step of {title}", lam="") or Expr("0.0", lam="")
        else:
            step = float(ode.step)
        # events
        events: list[EventPlan] = []
        for j, ev in enumerate(ode.events):
            epath = path + ("events", j)
            ename = ev.name or f"event {j + 1}"
            when = self.expr(epath + ("when",), f"the condition of event '{ename}'", lam="")
            if when is None:
                continue
            lines = self.code_lines(ev.action, epath + ("action",), f"the action of event '{ename}'")
            action = self.add_method(self.method_name(f"_on_{_slug(ename)}"), "self", "", lines) if lines else None
            events.append(EventPlan(ename, when, ev.direction, action, ev.stop, self.where(epath)))
        return OdePlan(
            title=title,
            independent=ind,
            rates=rates,
            method=ode.method,
            step=step,
            rates_method=rates_fn,
            preliminary=preliminary,
            events=events,
            tolerance=ode.tolerance,
            max_step=ode.max_step,
            enabled=page.enabled,
            where=self.where(path + ("equations",), key=True),
        )

    # -- assets ------------------------------------------------------------------------------------------
    def asset(self, rel: str, path: Path_, what: str = "asset") -> str | None:
        """Check a file inside the spec's folder (links followed; meshes read); register it to copy."""
        from ejsgen._assets import checked_asset

        try:
            name, real = checked_asset(self.spec_dir, rel, self.loc(path), what, mesh=what == "mesh file")
            meshes = []
            if name.lower().endswith(".urdf"):  # its meshes travel with it
                from ejsgen._assets import urdf_meshes

                meshes = [checked_asset(self.spec_dir, m, self.loc(path), "URDF mesh", mesh=True) for m in
                          urdf_meshes(self.spec_dir, real, name, self.loc(path))]
        except SpecError as err:
            self.errors.append(err)
            return None
        self.assets[name] = real
        self.assets.update(meshes)
        return name

    # -- the whole spec -----------------------------------------------------------------------------------
    def compile(self) -> AppPlan:
        from ejsgen._view_compile import ViewCompiler

        user_imports = self.compile_imports()
        defs = self.collect_custom_names()
        self.compile_variables()
        self.collect_preliminary_locals()
        for i, a in enumerate(self.spec.assets):
            self.asset(a, ("assets", i))
        self.compile_blocks()
        self.compile_custom(defs)
        self.compile_evolution()
        if self.spec.metrics:
            from ejsgen._metrics import compile_metrics

            compile_metrics(self)
        if self.spec.fmus:
            from ejsgen._fmu import compile_fmus

            compile_fmus(self)
        if self.spec.plant is not None:
            from ejsgen._spec_plant import compile_plant

            compile_plant(self)
        view = ViewCompiler(self).compile(self.checked.view)
        if self.spec.model.programs:
            from ejsgen._programs import compile_programs

            compile_programs(self)
            view = view + self.program_labels
        generated = {m.name for m in self.methods} - self.names.functions
        for v in self.checked.variables:  # the generated methods' names are known only now
            if v.name in generated:
                self.errors.append(SpecError(self.doc.key_loc(v.path), f"'{v.name}' is the name of a method the generated app defines", f"rename the variable (e.g. '{free_name(v.name, generated | set(self.var_decls))}')"))
        if self.errors:
            raise SpecErrors(_dedupe(self.errors))
        independent = self.independents[0] if self.independents else ("t" if "t" in self.var_decls else None)
        sim = self.spec.simulation
        return AppPlan(
            spec_name=self.spec_path.name,
            title=self.spec.title,
            description=self.spec.description,
            author=self.spec.author,
            user_imports=user_imports,
            variables=dict(self.var_types),
            independent=independent,
            methods=self.methods,
            view=view,
            sim={"fps": sim.fps, "steps_per_display": sim.steps_per_display, "autoplay": sim.autoplay, "realtime": sim.realtime, "controls": sim.controls} | ({"panel_width": sim.panel_width} if sim.panel_width else {}),
            assets=sorted((src, rel) for rel, src in self.assets.items()),
            after_class=self.after_class,
            runtime_imports=self.runtime_imports,
            var_plans=self.var_plans,
            pages=self.pages,
            programs=self.programs,
        )


def _rename_import(stmt: ast.Import | ast.ImportFrom, alias: ast.alias, bound: str, taken: Any) -> str:
    """A hint: the same import binding a free name, e.g. ``write 'from math import e as E_'``."""
    from_math = isinstance(stmt, ast.ImportFrom) and stmt.module == "math" and alias.name == bound
    if bound in PRELUDE_NAMES and (from_math or (bound == "np" and alias.name == "numpy")):
        return "the prelude already has it: remove this import"
    fixed = ast.alias(name=alias.name, asname=free_name(bound, taken))
    one = ast.ImportFrom(module=stmt.module, names=[fixed], level=0) if isinstance(stmt, ast.ImportFrom) else ast.Import(names=[fixed])
    return f"import it under another name, e.g. '{ast.unparse(one)}'"


def _dedupe(errors: list[SpecError]) -> list[SpecError]:
    seen = set()
    out = []
    for e in errors:
        key = (str(e.where), e.message)
        if key not in seen:
            seen.add(key)
            out.append(e)
    return out


def _is_self_attr(node: ast.AST) -> bool:
    return isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self"


def _get(data: Any, path: Path_) -> Any:
    cur = data
    for key in path:
        try:
            cur = cur[key]
        except (KeyError, IndexError, TypeError):
            return {}
    return cur


def _shape_text(shape: tuple[int, ...]) -> str:
    return "()" if not shape else "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _literal_source(value: Any) -> tuple[str, str, tuple[int, ...] | None, str]:
    """Source, value type, shape and an error text ('' if fine) for a plain initial value."""
    if isinstance(value, bool):
        return repr(value), "bool", (), ""
    if isinstance(value, int):
        return repr(value), "int", (), ""
    if isinstance(value, float):
        return repr(value), "float", (), ""
    if isinstance(value, str):
        return repr(value), "str", (), ""
    if value is None:
        return "None", "object", None, ""
    if isinstance(value, list):
        shape, err = literal_shape(value)
        if err:
            return "", "", None, err
        return f"np.array({py(_floats(value))}, dtype=float)", "array", shape, ""
    if isinstance(value, dict):
        return "", "", None, "a mapping is not a value; the long form takes 'value' or 'expr' (with doc, unit, min, max)"
    return "", "", None, f"unsupported initial value {value!r}"


def _floats(value: Any) -> Any:
    if isinstance(value, list):
        return [_floats(v) for v in value]
    return float(value)


def compile_spec(checked: Checked, spec_path: Path) -> AppPlan:
    """Compile a validated spec (raises ``SpecErrors``)."""
    return Compiler(checked, spec_path).compile()



def _slug(text: str) -> str:
    """A method-name part from a name or label: ``"Solve and move"`` -> ``"solve_and_move"``."""
    import re

    return re.sub(r"\W+", "_", text.lower()).strip("_") or "x"


def _single_call(c: Compiler, path: Path_) -> str | None:
    """The name called when the code at ``path`` is one bare call of a custom function or a
    control with no arguments (``kick()``), else None."""
    text = _get(c.doc.data, path)
    try:
        tree = ast.parse(str(text).strip())
    except SyntaxError:
        return None
    if len(tree.body) != 1 or not isinstance(tree.body[0], ast.Expr):
        return None
    call = tree.body[0].value
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and not call.args and not call.keywords):
        return None
    name = call.func.id
    return name if name in c.names.functions or name in c.names.controls else None


def _custom_source(snippet: Snippet, fn: ast.FunctionDef) -> list[Line] | None:
    """A custom function as the author wrote it (with the comments right above it), names
    rewritten and ``self`` added as its first parameter; None if the text cannot be kept."""
    import re

    end = fn.end_lineno or fn.lineno
    all_lines = snippet.text.split("\n")
    start = fn.lineno
    while start > 1 and all_lines[start - 2].strip().startswith("#"):
        start -= 1
    text = rewrite_source(snippet, ast.Module(body=[fn], type_ignores=[]), lines=(start, end))
    if text is None:
        return None
    out = source_lines(snippet, text, first_line=start)
    k = fn.lineno - start
    def_line = out[k][0]
    a = fn.args
    has_args = bool(a.posonlyargs or a.args or a.vararg or a.kwonlyargs or a.kwarg)
    m = re.match(rf"(\s*def\s+{re.escape(fn.name)}\s*\()", def_line)
    if m is None:
        return None
    out[k] = (def_line[: m.end()] + ("self, " if has_args else "self") + def_line[m.end():], out[k][1])
    return [Line(t, w) for t, w in out]
