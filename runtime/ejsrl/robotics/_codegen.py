"""Straight-line code generation for one robot's kinematics and dynamics (private).

An algorithm (forward kinematics, RNE...) is written once with ordinary arithmetic and
run on :class:`Var` symbols instead of numbers. Every operation that involves a symbol
is recorded on a :class:`Tape`; operations on plain floats (the robot's constant
parameters) are done at once by Python. Multiplying by an exact 0 or 1 is dropped, so
the terms that vanish for this arm (``cos(pi/2)``, ``a = 0``, a diagonal inertia...)
never reach the generated code. Repeated sub-expressions are shared, unused ones
removed, and temporaries reuse a few names so memory stays bounded.

The result is the source of one Python function with no loops and no calls but
``sin``/``cos``. It is compiled twice: on plain floats with ``math.sin`` for one
configuration (no NumPy call overhead at all), and on ``(m,)`` arrays with ``np.sin``
for a batch (one vectorised operation per scalar operation).
"""

from __future__ import annotations

import math
import threading
from typing import Callable, Sequence, Union

import numpy as np

Scalar = Union[float, "Var"]

_STATE = threading.local()  # .tape: the Tape recording in this thread


class Var:
    """A symbol: ``-name`` when ``neg`` else ``name``. Arithmetic records on the tape."""

    __slots__ = ("name", "neg")

    def __init__(self, name: str, neg: bool = False) -> None:
        self.name = name
        self.neg = neg

    def __neg__(self) -> "Var":
        return Var(self.name, not self.neg)

    def __pos__(self) -> "Var":
        return self

    def __add__(self, other: Scalar) -> Scalar:
        return _add(self, other)

    __radd__ = __add__

    def __sub__(self, other: Scalar) -> Scalar:
        return _add(self, -other)

    def __rsub__(self, other: Scalar) -> Scalar:
        return _add(-self, other)

    def __mul__(self, other: Scalar) -> Scalar:
        return _mul(self, other)

    __rmul__ = __mul__

    def __truediv__(self, other: Scalar) -> Scalar:
        return _div(self, other)

    def __rtruediv__(self, other: Scalar) -> Scalar:
        return _div(other, self)


def _tape() -> "Tape":
    tape = getattr(_STATE, "tape", None)
    if tape is None:
        raise RuntimeError("symbolic arithmetic outside a Tape")
    return tape


def _add(x: Var, y: Scalar) -> Scalar:
    if isinstance(y, Var):
        if x.neg and y.neg:
            return -_tape().op("+", Var(x.name), Var(y.name))
        if x.neg:
            return _tape().op("-", Var(y.name), Var(x.name))
        if y.neg:
            return _tape().op("-", x, Var(y.name))
        return _tape().op("+", x, y)
    if y == 0.0:
        return x
    if x.neg:
        return _tape().op("-", float(y), Var(x.name))
    return _tape().op("+", x, float(y)) if y > 0 else _tape().op("-", x, -float(y))


def _mul(x: Var, y: Scalar) -> Scalar:
    if isinstance(y, Var):
        out = _tape().op("*", Var(x.name), Var(y.name))
        return -out if x.neg != y.neg else out
    if y == 0.0:
        return 0.0
    if y == 1.0:
        return x
    if y == -1.0:
        return -x
    out = _tape().op("*", Var(x.name), abs(float(y)))
    return -out if x.neg != (y < 0) else out


def _div(x: Scalar, y: Scalar) -> Scalar:
    neg = False
    if isinstance(x, Var):
        neg, x = x.neg, Var(x.name)
    elif x < 0:
        neg, x = True, -float(x)
    if isinstance(y, Var):
        neg, y = neg != y.neg, Var(y.name)
    elif y == 1.0:
        return -x if neg else x
    out = _tape().op("/", x, y)
    return -out if neg else out


def sin(x: Scalar) -> Scalar:
    """``sin`` of a float (computed now) or of a symbol (recorded)."""
    if not isinstance(x, Var):
        return math.sin(x)
    out = _tape().call("sin", Var(x.name))
    return -out if x.neg else out


def cos(x: Scalar) -> Scalar:
    """``cos`` of a float (computed now) or of a symbol (recorded)."""
    if not isinstance(x, Var):
        return math.cos(x)
    return _tape().call("cos", Var(x.name))


def step(x: Scalar, sign: float) -> Scalar:
    """1.0 where ``sign * x > 0`` else 0.0 (a bool in the generated code, which multiplies
    like 0/1 for floats and arrays alike)."""
    if not isinstance(x, Var):
        return float(sign * x > 0)
    return _tape().call("gt0" if (sign > 0) != x.neg else "lt0", Var(x.name))


def snap(x: float) -> float:
    """Round values within 1e-12 of 0, 1 or -1 to them (``cos(pi/2)`` is 6e-17), so that
    the terms they multiply vanish from the generated code."""
    for v in (0.0, 1.0, -1.0):
        if abs(x - v) < 1e-12:
            return v
    return float(x)


def _atom(x: Scalar) -> str:
    if isinstance(x, Var):
        return x.name
    return repr(float(x))


class Tape:
    """Records operations on symbols and turns them into a function's source.

    Use as a context manager; ``inputs(names)`` makes the arguments."""

    def __init__(self) -> None:
        self.lines: list[tuple[str, str, str, str]] = []  # target, op, a, b
        self.cse: dict[tuple[str, str, str], str] = {}
        self.names: set[str] = set()
        self._prev: Tape | None = None

    def __enter__(self) -> "Tape":
        self._prev, _STATE.tape = getattr(_STATE, "tape", None), self
        return self

    def __exit__(self, *exc: object) -> None:
        _STATE.tape = self._prev

    def inputs(self, prefix: str, n: int) -> list[Var]:
        return [Var(f"{prefix}{i}") for i in range(n)]

    def _emit(self, op: str, a: str, b: str) -> Var:
        key = (op, a, b)
        name = self.cse.get(key)
        if name is None:
            name = f"t{len(self.lines)}"
            self.lines.append((name, op, a, b))
            self.names.add(name)
            self.cse[key] = name
        return Var(name)

    def op(self, op: str, x: Scalar, y: Scalar) -> Var:
        """``x op y`` for non-negated symbols or floats (not both floats)."""
        a, b = _atom(x), _atom(y)
        if op in "+*" and b < a:
            a, b = b, a
        return self._emit(op, a, b)

    def call(self, fn: str, x: Var) -> Var:
        return self._emit(fn, x.name, "")

    def source(self, name: str, args: Sequence[str], outputs: Sequence[Scalar]) -> str:
        """Source of ``def name(*args): ... return (outputs)``.

        Dead code is removed; a temporary used once is written into the expression that
        uses it (fewer loads and stores); the others reuse names once their value is no
        longer needed, so at most a few dozen arrays are alive in the batched version."""
        temps = self.names
        out_names = {o.name for o in outputs if isinstance(o, Var)}
        live = set(out_names)
        kept = []
        for line in reversed(self.lines):
            if line[0] in live:
                kept.append(line)
                live.update(line[2:])
        kept.reverse()
        uses: dict[str, int] = {}
        for _, _, a, b in kept:
            for d in (a, b):
                uses[d] = uses.get(d, 0) + 1
        inline: dict[str, tuple[tuple, int]] = {}  # temp -> (expression node, depth)
        lines: list[tuple[str, tuple, set[str]]] = []  # target, node, names read
        for target, op, a, b in kept:
            depth = 0
            reads: set[str] = set()
            operands = []
            for d in (a, b):
                if d in inline:
                    node, dd = inline.pop(d)
                    operands.append(node)
                    depth = max(depth, dd)
                    reads |= node[3]
                else:
                    operands.append(d)
                    if d in temps or d in args:
                        reads.add(d)
            node = (op, operands[0], operands[1], reads)
            if uses.get(target) == 1 and target not in out_names and depth < _MAX_DEPTH:
                inline[target] = (node, depth + 1)
            else:
                lines.append((target, node, reads))
        last: dict[str, int] = {}
        for i, (_, _, reads) in enumerate(lines):
            for d in reads:
                last[d] = i
        rename: dict[str, str] = {}
        free: list[str] = []
        body = []
        for i, (target, node, reads) in enumerate(lines):
            expr = _render(node, rename)
            for d in reads:
                if d in temps and last[d] == i and d not in out_names:
                    free.append(rename[d])
            new = free.pop() if free else f"v{len(rename)}"
            rename[target] = new
            body.append(f"    {new} = {expr}")
        rets = []
        for o in outputs:
            if isinstance(o, Var):
                rets.append(("-" if o.neg else "") + rename.get(o.name, o.name))
            else:
                rets.append(repr(float(o)))
        head = f"def {name}({', '.join(args)}):"
        return "\n".join([head, *body, f"    return ({', '.join(rets)},)", ""])


_MAX_DEPTH = 12  # nesting of inlined expressions
_COMPARE = {"gt0": "> 0.0", "lt0": "< 0.0"}


def _render(node: tuple | str, rename: dict[str, str]) -> str:
    if isinstance(node, str):
        return rename.get(node, node)
    op, a, b, _ = node
    if op in ("sin", "cos"):
        return f"{op}({_render(a, rename)})"
    if op in _COMPARE:
        return f"({_render(a, rename)} {_COMPARE[op]})"
    ra = _render(a, rename)
    if not isinstance(a, str):
        ra = f"({ra})"
    rb = _render(b, rename)
    if not isinstance(b, str):
        rb = f"({rb})"
    return f"{ra} {op} {rb}"


_FLOAT_NS = {"sin": math.sin, "cos": math.cos, "inf": math.inf, "nan": math.nan}
_ARRAY_NS = {"sin": np.sin, "cos": np.cos, "inf": math.inf, "nan": math.nan}


def compile_pair(src: str, name: str) -> tuple[Callable[..., tuple], Callable[..., tuple]]:
    """The function in ``src`` compiled for floats and for ``(m,)`` arrays."""
    code = compile(src, f"<ejsrl.robotics generated {name}>", "exec")
    fns = []
    for ns in (_FLOAT_NS, _ARRAY_NS):
        scope = dict(ns)
        exec(code, scope)  # noqa: S102 - our own generated arithmetic
        fns.append(scope[name])
    return fns[0], fns[1]


def trace(fn: Callable[..., Sequence[Scalar]], name: str, arg_groups: Sequence[tuple[str, int]]) -> str:
    """Run ``fn`` on symbols (one list per ``(prefix, size)`` group) and return the
    generated source of a function taking all of them as flat arguments."""
    with Tape() as tape:
        groups = [tape.inputs(p, k) for p, k in arg_groups]
        outputs = list(fn(*groups))
        args = [v.name for g in groups for v in g]
        return tape.source(name, args, outputs)
