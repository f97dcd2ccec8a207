"""Parse spec snippets with ``ast``, resolve their names, and rewrite them for the model class.

The language's rules (spec-language.md, "Values, expressions and code"):

- model variables are read and assigned by bare name -> ``self.name``;
- custom functions are called by bare name -> ``self.name(...)``; assigning to one is an error;
- the prelude's simulation and world controls -> ``self.name(...)``;
- ``np``, the ``math`` names, names bound by ``imports`` and Python's builtins stay globals;
- any other name assigned in a block is a local of that block; function parameters,
  lambda parameters and comprehension variables are locals of their own scope;
- any other name is an error, reported at its spec location with the closest known name.
"""

from __future__ import annotations

import ast
import builtins
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from ejsgen._assets import ASSET_FUNCTION, asset_call, opens_an_asset, unlisted_file
from ejsgen._code_bounds import MAX_CODE_DEPTH, heaviest_statement, too_deep
from ejsgen._power import power_text
from ejsgen._suggest import did_you_mean, module_hint
from ejsgen.errors import CodeSyntaxError, Location, SpecError, UnknownNameError
from ejsgen.validate import MATH_NAMES
from ejsgen.yamlload import TextOrigin
from ejsrl.sim.names import MATH_CONSTANTS as _MATH_CONSTANTS

__all__ = ["Names", "Snippet", "assigned_names", "parse_snippet", "rewrite", "rewrite_source", "source_lines", "BUILTIN_NAMES"]

BUILTIN_NAMES = frozenset(n for n in dir(builtins) if not n.startswith("_")) - {
    "eval",
    "exec",
    "compile",
    "__import__",
    "globals",
    "locals",
    "vars",
    "open",
    "input",
    "breakpoint",
    "exit",
    "quit",
    "help",
    "copyright",
    "credits",
    "license",
}


@dataclass
class Names:
    """What names mean in a spec.

    ``variables``: model variables; ``functions``: custom function names; ``controls``:
    prelude names that become model methods; ``globals``: names that stay module globals
    (``np``, math names, imported names); ``extra``: names valid only in some blocks
    (e.g. a program's motion commands), which become model methods too.
    """

    variables: set[str]
    functions: set[str]
    controls: set[str]
    globals: set[str]
    extra: set[str] = field(default_factory=set)
    #: the strings that name a listed asset (``ejsgen._assets.asset_names``): each becomes ``asset('...')``
    assets: frozenset[str] = frozenset()
    #: the spec's folder: a call naming a file there that is not an asset is an error
    spec_dir: Path | None = None
    #: names that are locals of one block only (a ``preliminary``'s, seen by its page's rates):
    #: name -> (where it is visible, how to share it), said when another block uses the name
    elsewhere: dict[str, tuple[str, str]] = field(default_factory=dict)

    def known(self) -> set[str]:
        return self.variables | self.functions | self.controls | self.globals | self.extra | set(BUILTIN_NAMES)


@dataclass
class Snippet:
    """Code or an expression from the spec: its ``text``, where it starts, and what it is."""

    text: str
    origin: TextOrigin
    file: str
    what: str  # e.g. "model.init", "view slider on_change"
    mode: str = "exec"  # "exec" or "eval"

    def location(self, lineno: int, col_offset: int) -> Location:
        """The spec location of a position (1-based line, 0-based col) in the snippet."""
        line = self.origin.line + max(lineno, 1) - 1
        if self.origin.block or lineno <= 1:
            return Location(self.file, line, self.origin.col + col_offset)
        return Location(self.file, line, col_offset + 1)


def parse_snippet(snippet: Snippet) -> ast.AST:
    """Parse a snippet; a Python syntax error becomes a ``SpecError`` at its spec location."""
    text = snippet.text
    if snippet.mode == "eval":
        if not text.strip():
            raise SpecError(snippet.location(1, 0), f"empty expression in {snippet.what}")
    if snippet.mode == "eval":
        text = "(" + text + "\n)"  # allows leading spaces and line breaks; shifts line 1 by one column
    try:
        tree = ast.parse(text, mode=snippet.mode, type_comments=False)
    except SyntaxError as exc:
        lineno = exc.lineno or 1
        col = (exc.offset or 1) - 1
        lines = snippet.text.splitlines() or [""]
        if lineno > len(lines):  # at the end of the text (e.g. a trailing operator)
            lineno, col = len(lines), len(lines[-1].rstrip())
        elif snippet.mode == "eval" and lineno == 1:
            col = max(col - 1, 0)
        msg = exc.msg
        opener = _unclosed_bracket(snippet.text) if snippet.mode == "eval" and "does not match" in msg else None
        if opener is not None:  # the closing ')' Python saw is our wrapper's: the opener is the problem
            (lineno, col), msg = opener[1:], f"'{opener[0]}' was never closed"
        if msg.startswith("unexpected indent") or msg.startswith("unindent"):
            msg += " (code in a YAML block starts at the block's indentation)"
        if msg == "unexpected EOF while parsing" or "was never closed" in msg:
            msg = msg.replace("'('", "a parenthesis") if snippet.mode == "eval" else msg
        raise CodeSyntaxError(snippet.location(lineno, col), f"Python syntax error in {snippet.what}: {msg}") from None
    except (RecursionError, MemoryError):
        tree = None
    deep = too_deep(tree) if tree is not None else None
    if tree is None or deep is not None:
        line, col = heaviest_statement(snippet.text) if tree is None else (getattr(deep, "lineno", 1), getattr(deep, "col_offset", 0))
        where = snippet.location(line, col)
        raise SpecError(where, f"the code in {snippet.what} nests more than {MAX_CODE_DEPTH} levels deep", "split it into steps with names") from None
    if snippet.mode == "eval":
        for node in ast.walk(tree):
            if getattr(node, "lineno", None) == 1:
                node.col_offset = max(node.col_offset - 1, 0)  # type: ignore[attr-defined]
            if getattr(node, "end_lineno", None) == 1 and node.end_col_offset is not None:  # type: ignore[attr-defined]
                node.end_col_offset = max(node.end_col_offset - 1, 0)  # type: ignore[attr-defined]
    return tree


#: builtins that code uses without calling them (``dtype=float``)
_VALUE_BUILTINS = frozenset({"float", "int", "bool", "complex", "str", "list", "tuple", "dict", "set"})
#: words that YAML 1.1 reads as booleans; in specs they are text, and in code they are names
_YAML11_WORDS = ("yes", "no", "on", "off")


def _unclosed_bracket(text: str) -> tuple[str, int, int] | None:
    """The innermost bracket of ``text`` left open at its end: (char, 1-based line, 0-based col).

    Strings and comments are skipped; None if every bracket is closed (or one is closed by
    the wrong kind, which Python's own message explains).
    """
    pairs = {")": "(", "]": "[", "}": "{"}
    stack: list[tuple[str, int, int]] = []
    line, col, i, n = 1, 0, 0, len(text)
    while i < n:
        ch = text[i]
        if ch in "\"'":
            quote = text[i : i + 3] if text[i : i + 3] in ('"""', "'''") else ch
            j = i + len(quote)
            while j < n and not text.startswith(quote, j):
                if text[j] == "\\":
                    j += 1
                elif text[j] == "\n" and len(quote) == 1:
                    return None  # an unterminated string: Python reports it well
                j += 1
            if j >= n:
                return None
            end = j + len(quote)
            skipped = text[i:end]
            if "\n" in skipped:
                line += skipped.count("\n")
                col = len(skipped) - skipped.rfind("\n") - 1
            else:
                col += len(skipped)
            i = end
            continue
        if ch == "#":
            while i < n and text[i] != "\n":
                i += 1
            continue
        if ch in "([{":
            stack.append((ch, line, col))
        elif ch in pairs:
            if not stack or stack[-1][0] != pairs[ch]:
                return None
            stack.pop()
        if ch == "\n":
            line, col = line + 1, 0
        else:
            col += 1
        i += 1
    return stack[-1] if stack else None


# -- scope analysis ---------------------------------------------------------------------------------


def _target_names(node: ast.AST) -> Iterable[str]:
    if isinstance(node, ast.Name):
        yield node.id
    elif isinstance(node, (ast.Tuple, ast.List)):
        for elt in node.elts:
            yield from _target_names(elt)
    elif isinstance(node, ast.Starred):
        yield from _target_names(node.value)


def _assigned_in(body: list[ast.stmt] | ast.AST) -> set[str]:
    """Names bound in a scope (not descending into nested functions, lambdas, comprehensions)."""
    out: set[str] = set()
    stack: list[ast.AST] = list(body) if isinstance(body, list) else [body]
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            out.add(node.name)
            for d in node.decorator_list:
                stack.append(d)
            if not isinstance(node, ast.ClassDef):
                stack.extend(node.args.defaults)
                stack.extend(d for d in node.args.kw_defaults if d is not None)
            continue
        if isinstance(node, (ast.Lambda, ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)):
            continue
        if isinstance(node, (ast.Assign,)):
            for t in node.targets:
                out.update(_target_names(t))
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            out.update(_target_names(node.target))
        elif isinstance(node, (ast.For, ast.AsyncFor)):
            out.update(_target_names(node.target))
        elif isinstance(node, ast.withitem) and node.optional_vars is not None:
            out.update(_target_names(node.optional_vars))
        elif isinstance(node, ast.ExceptHandler) and node.name:
            out.add(node.name)
        elif isinstance(node, ast.NamedExpr):
            out.update(_target_names(node.target))
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                out.add((alias.asname or alias.name).split(".")[0])
        stack.extend(ast.iter_child_nodes(node))
    return out


def assigned_names(body: list[ast.stmt]) -> set[str]:
    """The names a block of statements binds (its locals, before model variables are taken out)."""
    return _assigned_in(body)


def _arg_names(args: ast.arguments) -> set[str]:
    names = {a.arg for a in args.posonlyargs + args.args + args.kwonlyargs}
    if args.vararg:
        names.add(args.vararg.arg)
    if args.kwarg:
        names.add(args.kwarg.arg)
    return names


class _Rewriter(ast.NodeTransformer):
    """Rewrites names to model attributes and collects unknown-name errors."""

    def __init__(self, names: Names, snippet: Snippet, block_locals: set[str]) -> None:
        self.names = names
        self.snippet = snippet
        self.scopes: list[set[str]] = [block_locals]
        self.errors: list[SpecError] = []
        self._called: set[int] = set()
        self._attribute_bases: set[int] = set()  # names written as ``name.attr`` (a module, if unknown)
        self._asset_open: set[int] = set()  # ``open`` names that read an asset, strings already in asset(...)

    # scope helpers
    def _is_local(self, name: str) -> bool:
        # innermost scopes first; function parameters shadow model names
        for scope in reversed(self.scopes):
            if name in scope:
                return True
        return False

    def _err(self, node: ast.AST, message: str, hint: str = "", *, kind: type[SpecError] = SpecError) -> None:
        self.errors.append(kind(self.snippet.location(node.lineno, node.col_offset), message, hint))  # type: ignore[attr-defined]

    def _model_attr(self, node: ast.Name) -> ast.Attribute:
        attr = ast.Attribute(value=ast.Name(id="self", ctx=ast.Load()), attr=node.id, ctx=node.ctx)
        attr._ejs_prefix = "self."  # type: ignore[attr-defined]  # for rewrite_source
        return ast.copy_location(attr, node)

    def visit_Name(self, node: ast.Name) -> ast.AST:
        name = node.id
        store = isinstance(node.ctx, (ast.Store, ast.Del))
        if name == "self" and store and name not in self.names.variables:
            self._err(node, "'self' cannot be assigned in spec code: the generated code uses it for the model", "choose another name (e.g. 'self_')")
            return node
        if name in self.names.functions:
            if store:
                self._err(node, f"cannot assign to '{name}': it is a custom function")
                return node
            return self._model_attr(node) if not self._is_local(name) else node
        if self._is_local(name) and (name not in self.names.variables or self._shadowing(name)):
            return node
        if name in self.names.variables:
            return self._model_attr(node)
        if name in self.names.controls or name in self.names.extra:
            if store:
                self._err(node, f"cannot assign to '{name}': it is a prelude name")
                return node
            return self._model_attr(node)
        if name in self.names.globals or name in BUILTIN_NAMES:
            if store:
                self._err(node, f"cannot assign to '{name}': it is a prelude or imported name")
            return node
        if name == "self":
            self._err(node, "'self' is not a name in spec code", "use the variables' names directly")
            return node
        if name == "open" and id(node) in self._asset_open:
            return node
        if name in ("eval", "exec", "compile", "__import__", "globals", "locals", "vars", "open", "input", "breakpoint"):
            if name == "open":
                self._err(node, "'open' is not available in spec code, except to read a file listed under 'assets:'", "list the file under assets: and open it by its path, e.g. open('notes.txt')")
                return node
            self._err(node, f"'{name}' is not available in spec code")
            return node
        if name in self.names.elsewhere:
            visible, share = self.names.elsewhere[name]
            self._err(node, f"unknown name '{name}' here: {visible}", share, kind=UnknownNameError)
            return node
        hint = module_hint(name) if id(node) in self._attribute_bases else ""
        self._err(node, f"unknown name '{name}'", hint or self._suggest(name, called=id(node) in self._called), kind=UnknownNameError)
        return node

    def _suggest(self, name: str, *, called: bool) -> str:
        """The closest name that fits where ``name`` stands, the spec's own names first.

        A called name is looked for among functions, any other among values; the spec's
        variables, functions and locals come before the prelude and imports, and Python's
        builtins (``range``, ``round``...) are suggested last, only when very close.
        """
        lower = name.lower()
        if lower in _YAML11_WORDS:
            value = "True" if lower in ("yes", "on") else "False"
            return f"did you mean {value.lower()} ({value} in code)? in specs only true and false are booleans; yes, no, on and off are text"
        n = self.names
        local = set().union(*self.scopes)
        math_functions = set(MATH_NAMES) - _MATH_CONSTANTS
        if called:
            tiers = [(n.functions | n.extra | local, 0.6), (n.controls | n.globals, 0.6), (set(BUILTIN_NAMES), 0.8)]
        else:
            tiers = [
                (n.variables | local, 0.6),
                (n.globals - math_functions, 0.6),
                (n.functions | n.extra | n.controls | math_functions | (_VALUE_BUILTINS & BUILTIN_NAMES), 0.8),
            ]
        for candidates, cutoff in tiers:
            hint = did_you_mean(name, candidates, cutoff=cutoff)
            if hint:
                return hint
        return ""

    # ``^`` is Python's exclusive or; authors coming from EJS's Java, MATLAB or a calculator
    # mean a power by it. It is refused everywhere (bitwise xor is rare in labs and has a
    # spelling that says what it is), pointing at the operator.
    def _caret_at(self, left: ast.AST, right: ast.AST) -> tuple[int, int]:
        """(line, col) of the ``^`` between ``left`` and ``right`` in the snippet's text."""
        lines = self.snippet.text.split("\n")
        row, col = left.end_lineno or left.lineno, left.end_col_offset or 0  # type: ignore[attr-defined]
        while row <= len(lines):
            raw = lines[row - 1].encode("utf-8")
            at = raw.find(b"^", col)
            if at >= 0:
                return row, at
            row, col = row + 1, 0
        return right.lineno, right.col_offset  # type: ignore[attr-defined]

    def visit_BinOp(self, node: ast.BinOp) -> ast.AST:
        if isinstance(node.op, ast.BitXor):
            line, col = self._caret_at(node.left, node.right)
            power = power_text(self.snippet.text.split("\n")[line - 1], col) or f"{ast.unparse(node.left)}**{ast.unparse(node.right)}"
            self.errors.append(SpecError(
                self.snippet.location(line, col),
                "'^' is not a power in Python: it is the bitwise exclusive or",
                f"did you mean {power!r} (** is the power)? for an exclusive or write np.bitwise_xor(a, b), or a != b for true/false",
            ))
        return self.generic_visit(node)

    def visit_AugAssign(self, node: ast.AugAssign) -> ast.AST:
        if isinstance(node.op, ast.BitXor):
            line, col = self._caret_at(node.target, node.value)
            target = ast.unparse(node.target)
            self.errors.append(SpecError(
                self.snippet.location(line, col),
                "'^=' is not a power in Python: it is the bitwise exclusive or",
                f"did you mean '{target} **= {ast.unparse(node.value)}' (** is the power)? for an exclusive or write {target} = np.bitwise_xor({target}, ...)",
            ))
        return self.generic_visit(node)

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        if isinstance(node.value, ast.Name):
            self._attribute_bases.add(id(node.value))
        return self.generic_visit(node)

    def visit_Call(self, node: ast.Call) -> ast.AST:
        if isinstance(node.func, ast.Name):
            self._called.add(id(node.func))
            if node.func.id == "open" and opens_an_asset(node, self.names.assets):
                self._asset_open.add(id(node.func))
            if node.func.id == ASSET_FUNCTION:  # asset('data.csv') written out: already the path
                self._asset_open.update(id(a) for a in node.args)
        ours = not (self._is_local(ASSET_FUNCTION) or ASSET_FUNCTION in self.names.variables | self.names.functions)
        problem = unlisted_file(node, self.names.assets, self.names.spec_dir, asset_is_ours=ours)
        if problem is not None:
            self._err(*problem)
        return self.generic_visit(node)

    def _shadowing(self, name: str) -> bool:
        """A parameter/comprehension/lambda scope (not the block) binds ``name``."""
        return any(name in scope for scope in self.scopes[1:])

    # nested scopes
    def _function(self, node: ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda) -> ast.AST:
        a = node.args
        for arg in a.posonlyargs + a.args + a.kwonlyargs + [x for x in (a.vararg, a.kwarg) if x is not None]:
            if arg.arg == "self":
                self._err(arg, "a parameter cannot be named 'self': the generated code uses it for the model", "choose another name (e.g. 'self_')")
        node.args = self.visit(node.args)
        if isinstance(node, ast.Lambda):
            self.scopes.append(_arg_names(node.args))
            node.body = self.visit(node.body)
        else:
            node.decorator_list = [self.visit(d) for d in node.decorator_list]
            if node.returns is not None:
                node.returns = self.visit(node.returns)
            local = _arg_names(node.args) | (_assigned_in(node.body) - self.names.variables)
            self.scopes.append(local)
            node.body = [self.visit(s) for s in node.body]
        self.scopes.pop()
        return node

    def visit_arguments(self, node: ast.arguments) -> ast.AST:
        node.defaults = [self.visit(d) for d in node.defaults]
        node.kw_defaults = [self.visit(d) if d is not None else None for d in node.kw_defaults]
        return node

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.AST:
        return self._function(node)

    def visit_AsyncFunctionDef(self, node: ast.AsyncFunctionDef) -> ast.AST:
        return self._function(node)

    def visit_Lambda(self, node: ast.Lambda) -> ast.AST:
        return self._function(node)

    def _comprehension(self, node: ast.ListComp | ast.SetComp | ast.GeneratorExp | ast.DictComp) -> ast.AST:
        bound: set[str] = set()
        for gen in node.generators:
            bound.update(_target_names(gen.target))
        # the first iterable is evaluated in the enclosing scope
        node.generators[0].iter = self.visit(node.generators[0].iter)
        self.scopes.append(bound)
        for i, gen in enumerate(node.generators):
            gen.target = self.visit(gen.target)
            if i:
                gen.iter = self.visit(gen.iter)
            gen.ifs = [self.visit(x) for x in gen.ifs]
        if isinstance(node, ast.DictComp):
            node.key = self.visit(node.key)
            node.value = self.visit(node.value)
        else:
            node.elt = self.visit(node.elt)
        self.scopes.pop()
        return node

    visit_ListComp = _comprehension
    visit_SetComp = _comprehension
    visit_GeneratorExp = _comprehension
    visit_DictComp = _comprehension

    def visit_Global(self, node: ast.Global) -> ast.AST:
        self._err(node, "'global' is not needed in spec code", "model variables are assigned by their bare names")
        return node

    def visit_Nonlocal(self, node: ast.Nonlocal) -> ast.AST:
        self._err(node, "'nonlocal' is not supported in spec code")
        return node

    def visit_Import(self, node: ast.Import) -> ast.AST:
        self._err(node, "imports go in the spec's 'imports' list, not inside code")
        return node

    visit_ImportFrom = visit_Import  # type: ignore[assignment]

    # an asset named by its path: the app's real path of the file, wherever the app runs
    def visit_Constant(self, node: ast.Constant) -> ast.AST:
        if not (isinstance(node.value, str) and node.value in self.names.assets) or id(node) in self._asset_open:
            return node
        if self._is_local(ASSET_FUNCTION):
            self._err(node, f"'{node.value}' names an asset, but '{ASSET_FUNCTION}' is a local name here", f"rename the local '{ASSET_FUNCTION}': the app reads its assets through the function {ASSET_FUNCTION}()")
            return node
        return asset_call(node)

    def visit_JoinedStr(self, node: ast.JoinedStr) -> ast.AST:
        # the literal parts of an f-string stay text; only its {values} are code
        node.values = [self.visit(v) if isinstance(v, ast.FormattedValue) else v for v in node.values]
        return node

    def visit_ClassDef(self, node: ast.ClassDef) -> ast.AST:
        self._err(node, "class definitions are not supported in spec code")
        return node


def rewrite(tree: ast.AST, names: Names, snippet: Snippet, *, extra_locals: Iterable[str] = ()) -> tuple[ast.AST, list[SpecError]]:
    """Resolve and rewrite the names of a parsed snippet; returns (tree, errors)."""
    if isinstance(tree, ast.Module):
        block_locals = (_assigned_in(tree.body) - names.variables - names.functions) | set(extra_locals)
    else:
        block_locals = set(extra_locals)
    rw = _Rewriter(names, snippet, block_locals)
    new = rw.visit(tree)
    ast.fix_missing_locations(new)
    return new, rw.errors


def rewrite_source(snippet: Snippet, tree: ast.AST, lines: tuple[int, int] | None = None) -> str | None:
    """The author's own text of a rewritten snippet: comments, line breaks and spacing kept.

    The rewriter turns a name into ``self.name`` (and a program's motion command into
    ``yield from cmd.name``) by marking the new node with the text to put before the name;
    here that text is inserted at each such name of the snippet. The result is checked to
    mean exactly the rewritten tree; None if it does not (the caller then unparses).
    ``lines``: (first, last) line of the snippet that hold ``tree`` (a custom function).
    """
    span = lines
    lines = snippet.text.split("\n")
    edits: list[tuple[int, int, str]] = []
    for node in ast.walk(tree):
        wrap = getattr(node, "_ejs_wrap", None)
        if wrap is not None:  # asset('...') put around a string: (row, col, text) at its start and end
            arg = node.args[0]  # type: ignore[attr-defined]
            spots = ((arg.lineno - 1, arg.col_offset, wrap[0]), (arg.end_lineno - 1, arg.end_col_offset, wrap[1]))
            if any(row >= len(lines) for row, _, _ in spots):
                return None
            for row, offset, text in spots:
                edits.append((row, len(lines[row].encode("utf-8")[:offset].decode("utf-8", errors="replace")), text))
            continue
        prefix = getattr(node, "_ejs_prefix", None)
        if prefix is None:
            continue
        row = node.lineno - 1  # type: ignore[attr-defined]
        if row >= len(lines):
            return None
        line = lines[row]
        col = len(line.encode("utf-8")[: node.col_offset].decode("utf-8", errors="replace"))  # type: ignore[attr-defined]
        name = node.attr  # type: ignore[attr-defined]
        if not line[col:].startswith(name):
            return None
        edits.append((row, col, prefix))
    shift = _continuation_shift(lines, edits)
    for row, col, prefix in sorted(edits, reverse=True):
        lines[row] = lines[row][:col] + prefix + lines[row][col:]
    for row, extra in shift.items():
        lines[row] = " " * extra + lines[row]
    text = "\n".join(lines if span is None else lines[span[0] - 1 : span[1]])
    if snippet.mode == "eval":
        text = text.strip()
        if _has_comment(text):
            return None  # an expression is placed inside other code: a comment would cut it
    try:
        again = ast.parse(f"({text}\n)" if snippet.mode == "eval" else text, mode=snippet.mode)
    except SyntaxError:
        return None
    want = tree.body if isinstance(tree, ast.Expression) else tree
    got = again.body if isinstance(again, ast.Expression) else again
    if ast.unparse(got) != ast.unparse(want):
        return None
    if snippet.mode == "eval" and "\n" in text:
        try:
            ast.parse(text, mode="eval")
        except SyntaxError:
            text = f"({text})"
    return text


def source_lines(snippet: Snippet, text: str, first_line: int = 1) -> list[tuple[str, Location | None]]:
    """The lines of ``text`` (the snippet's own lines from ``first_line``), each with the spec
    location of its first character (None for blank and comment lines)."""
    out: list[tuple[str, Location | None]] = []
    for i, line in enumerate(text.split("\n"), start=first_line):
        body = line.strip()
        if not body or body.startswith("#"):
            out.append((line.rstrip(), None))
        else:
            out.append((line.rstrip(), snippet.location(i, len(line) - len(line.lstrip()))))
    return out


def _has_comment(text: str) -> bool:
    import io
    import tokenize

    try:
        return any(tok.type == tokenize.COMMENT for tok in tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError):
        return True


def _continuation_shift(lines: list[str], edits: list[tuple[int, int, str]]) -> dict[int, int]:
    """How far to move each continuation line (inside brackets) so that it stays aligned under
    the text of the line above once ``self.`` has been put into that line before its column."""
    import io
    import tokenize

    depth_at: dict[int, int] = {}
    in_string: set[int] = set()
    depth = 0
    try:
        for tok in tokenize.generate_tokens(io.StringIO("\n".join(lines)).readline):
            row = tok.start[0] - 1
            depth_at.setdefault(row, depth)
            if tok.type == tokenize.OP and tok.string in "([{":
                depth += 1
            elif tok.type == tokenize.OP and tok.string in ")]}":
                depth -= 1
            elif tok.type == tokenize.STRING and tok.end[0] > tok.start[0]:
                in_string.update(range(tok.start[0], tok.end[0]))
    except (tokenize.TokenError, SyntaxError):
        return {}
    added: dict[int, list[tuple[int, int]]] = {}
    for row, col, prefix in edits:
        added.setdefault(row, []).append((col, len(prefix)))
    shift: dict[int, int] = {}
    for row in range(1, len(lines)):
        if depth_at.get(row, 0) <= 0 or row in in_string or not lines[row].strip():
            continue
        indent = len(lines[row]) - len(lines[row].lstrip())
        above = row - 1
        extra = shift.get(above, 0) + sum(n for c, n in added.get(above, []) if c < indent - shift.get(above, 0))
        if extra:
            shift[row] = extra
    return shift
