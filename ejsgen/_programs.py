"""Compile ``model.programs``: each program becomes a generator method of the model.

A motion command written as a statement, ``move_j(target, time=3)``, becomes
``yield from cmd.move_j(target, time=3)``: it takes simulated time and the program goes on
when it finishes. The commands may appear only as statements of a program's code.
"""

from __future__ import annotations

import ast
import dataclasses
from typing import TYPE_CHECKING

from ejsgen._suggest import did_you_mean
from ejsgen.errors import SpecError
from ejsgen.plan import Call, Expr, Line, ProgramPlan
from ejsgen.validate import PROGRAM_COMMANDS
from ejsrl.sim.names import PROGRAM_RUNNER

if TYPE_CHECKING:
    from ejsgen.compiler import Compiler

__all__ = ["compile_programs", "PROGRAM_NAMES", "RUNNER"]

#: the motion commands, read from the runtime (the methods of ``ejsrl.sim.programs.Program`` marked as commands)
PROGRAM_NAMES = PROGRAM_COMMANDS
#: the name of the generator method's parameter through which commands run
RUNNER = PROGRAM_RUNNER


class _Commands(ast.NodeTransformer):
    """Turns statement calls of commands into ``yield from cmd.<command>(...)``; flags other uses."""

    def __init__(self, compiler: Compiler, snippet: object) -> None:
        self.c = compiler
        self.snippet = snippet
        self.errors: list[SpecError] = []

    @staticmethod
    def _command(node: ast.AST) -> str | None:
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and isinstance(node.func.value, ast.Name)
            and node.func.value.id == "self"
            and node.func.attr in PROGRAM_NAMES
        ):
            return node.func.attr
        return None

    def visit_Expr(self, node: ast.Expr) -> ast.AST:
        name = self._command(node.value)
        if name is None:
            self.generic_visit(node)
            return node
        call = node.value
        assert isinstance(call, ast.Call)
        call.args = [self.visit(a) for a in call.args]
        call.keywords = [self.visit(k) for k in call.keywords]
        call.func = ast.copy_location(ast.Attribute(value=ast.Name(id=RUNNER, ctx=ast.Load()), attr=name, ctx=ast.Load()), call.func)
        call.func._ejs_prefix = f"yield from {RUNNER}."  # type: ignore[attr-defined]  # for rewrite_source
        return ast.copy_location(ast.Expr(value=ast.copy_location(ast.YieldFrom(value=call), call)), node)

    def visit_Attribute(self, node: ast.Attribute) -> ast.AST:
        if isinstance(node.value, ast.Name) and node.value.id == "self" and node.attr in PROGRAM_NAMES:
            self.errors.append(
                SpecError(self.snippet.location(node.lineno, node.col_offset), f"'{node.attr}' is a motion command: write it as a statement of the program, e.g. {node.attr}(...)")  # type: ignore[attr-defined]
            )
        self.generic_visit(node)
        return node

    def visit_FunctionDef(self, node: ast.FunctionDef) -> ast.AST:
        self.errors.append(SpecError(self.snippet.location(node.lineno, node.col_offset), "define functions in 'custom', not inside a program"))  # type: ignore[attr-defined]
        return node

    visit_Lambda = ast.NodeTransformer.generic_visit


def compile_programs(c: Compiler) -> None:
    """Add a generator method per program, ``Model.PROGRAMS``, and a status label per program."""
    programs = c.spec.model.programs
    if not programs:
        return
    if not c.independents and "t" not in c.var_decls:
        first = next(iter(programs))
        c.errors.append(SpecError(c.doc.key_loc(("model", "programs", first)), "robot programs run in simulated time: the model needs an independent variable (an ODE page or a variable 't')"))
        return
    names = dataclasses.replace(c.names, extra=set(PROGRAM_NAMES))  # the spec's names (all of them), plus the commands
    for pname, prog in programs.items():
        path = ("model", "programs", pname)
        for key, what in (("robot", "Robot"), ("q", "joint-vector"), ("gripper", "gripper")):
            value = getattr(prog, key)
            if value is None:
                continue
            if value not in c.var_decls:
                c.errors.append(SpecError(c.loc(path + (key,)), f"the {what} variable '{value}' of program '{pname}' is not a variable", did_you_mean(value, c.var_decls)))
            elif key == "q" and c.var_types.get(value) not in ("array", "auto"):
                c.errors.append(SpecError(c.loc(path + (key,)), f"'{value}' must be a joint vector (a list of numbers), not {c.var_types.get(value)}"))
            elif key == "gripper" and c.var_types.get(value) not in ("float", "int", "auto"):
                c.errors.append(SpecError(c.loc(path + (key,)), f"the gripper variable '{value}' must be a number (0 closed to 1 open)"))
            elif key == "gripper" and c.var_types.get(value) == "int":
                c.var_types[value] = "float"
        lines: list[Line] = []
        code = prog.code
        pages = [(path + ("code",), code)] if isinstance(code, str) else [(path + ("code", i, "code"), p.code) for i, p in enumerate(code) if p.enabled]
        for cpath, _ in pages:
            snippet = c.snippet(cpath, f"program '{pname}'")
            tree = c.parse_rewrite(snippet, names=names)
            if tree is None:
                continue
            assert isinstance(tree, ast.Module)
            if RUNNER in {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}:
                c.errors.append(SpecError(c.loc(cpath), f"'{RUNNER}' is reserved inside programs; choose another local name"))
                continue
            tx = _Commands(c, snippet)
            tree = tx.visit(tree)
            c.errors.extend(tx.errors)
            ast.fix_missing_locations(tree)
            lines.extend(c.tree_lines(snippet, tree))
        method = c.method_name(f"_program_{pname}")
        c.add_method(method, f"self, {RUNNER}", f"Robot program '{pname}': each motion command takes simulated time ({RUNNER} runs them).", lines)
        where = c.where(path)
        c.programs.append(ProgramPlan(pname, method, prog.robot, prog.q, prog.gripper, prog.autostart, where))
        status = Expr(f"self._ejs_program_status({pname!r})", None, "", "self")
        c.program_labels.append(Call("E.Label", [], {"text": Call("E.Dynamic", [status, f"program {pname}"]), "where": where}))
