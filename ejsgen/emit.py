"""Lay out an ``AppPlan`` as Python text: calls, methods, the model's variables.

Every runtime call the app makes is a :class:`~ejsgen.plan.Call` in the plan; here it becomes
text, on one line when it fits in :data:`WIDTH` columns, else with its arguments filled over
lines under the opening parenthesis, and nested elements (``children``) one per line. Each
emitted line keeps the spec location of the first expression on it, for ``SPEC_LINES``.
"""

from __future__ import annotations

from typing import Any

from ejsgen.errors import Location
from ejsgen.plan import AppPlan, Call, EventPlan, Expr, Line, Method, OdePlan, Ref, Src, Variable, py

__all__ = ["WIDTH", "flat", "call_lines", "view_lines", "method_lines", "declare_method", "page_call", "module_calls", "used_names"]

#: the longest line the emitter writes when it can choose (spec text inside is kept as written)
WIDTH = 120


#: where the app's runtime calls come from: the first part of a call's name -> module
RUNTIME_MODULES = {
    "E": "ejsrl.view.elements",
    "OdePage": "ejsrl.sim",
    "CodePage": "ejsrl.sim",
    "EventDef": "ejsrl.sim",
    "SimConfig": "ejsrl.app",
    "AppMeta": "ejsrl.app",
    "ProgramDef": "ejsrl.sim.programs",
}


def runtime_callable(fn: str) -> Any:
    """The runtime object a call's dotted name means in app.py (``E.Slider``, ``OdePage.of``)."""
    import importlib

    head, *rest = fn.split(".")
    obj: Any = importlib.import_module(RUNTIME_MODULES[head])
    if head != "E":
        obj = getattr(obj, head)
    for part in rest:
        obj = getattr(obj, part)
    return obj


def runtime_defaults(fn: str) -> dict[str, Any]:
    """The keyword defaults of a runtime callable (plain values only)."""
    import inspect

    try:
        sig = inspect.signature(runtime_callable(fn))
    except (KeyError, ImportError, AttributeError, ValueError, TypeError):
        return {}
    plain = (type(None), bool, int, float, str, tuple)
    return {n: p.default for n, p in sig.parameters.items() if p.default is not inspect.Parameter.empty and type(p.default) in plain}


def kwargs_of(call: Call) -> dict[str, Any]:
    """The keyword arguments worth writing: those that differ from the runtime's defaults."""
    defaults = runtime_defaults(call.fn)
    out = {}
    for k, v in call.kwargs.items():
        if k in defaults and k not in call.keep and not isinstance(v, (Call, Expr, Ref, Src)) and type(v) is type(defaults[k]) and v == defaults[k]:
            continue
        out[k] = v
    return out


def flat(value: Any) -> str:
    """One-line source of a plan value."""
    if isinstance(value, Call):
        parts = [flat(a) for a in value.args] + [f"{k}={flat(v)}" for k, v in kwargs_of(value).items()]
        return f"{value.fn}({', '.join(parts)})"
    if isinstance(value, Expr):
        if value.lam is None:
            return value.source
        return f"lambda {value.lam}: {value.source}" if value.lam else f"lambda: {value.source}"
    if isinstance(value, Ref):
        return f"{value.owner}.{value.name}"
    if isinstance(value, list):
        return "[" + ", ".join(flat(v) for v in value) + "]"
    if isinstance(value, tuple):
        inner = ", ".join(flat(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{py(k)}: {flat(v)}" for k, v in value.items()) + "}"
    return py(value)


def _where(value: Any) -> Location | None:
    """The spec location of the first expression inside a value (for SPEC_LINES)."""
    if isinstance(value, Expr):
        return value.where
    if isinstance(value, Call):
        for v in [*value.args, *value.kwargs.values()]:
            w = _where(v)
            if w is not None:
                return w
    if isinstance(value, (list, tuple)):
        for v in value:
            w = _where(v)
            if w is not None:
                return w
    if isinstance(value, dict):
        return _where(list(value.values()))
    return None


def _fill(head: str, parts: list[tuple[str, Any]], tail: str, indent: int) -> list[Line]:
    """``head`` + parts separated by commas, wrapped under the column after ``head`` + ``tail``.

    A part too long for a line that is a list of calls, a dict or a text of several lines is
    laid out over lines of its own (one element, item or line of text each).
    """
    col = indent + len(head)
    hang = " " * col
    lines: list[Line] = []
    cur, where = " " * indent + head, None
    first = True
    for i, (text, value) in enumerate(parts):
        piece = text + (", " if i < len(parts) - 1 else "")
        if not first and len((cur + piece).rstrip()) + (len(tail) if i == len(parts) - 1 else 0) > WIDTH:
            lines.append(Line(cur.rstrip(), where))
            cur, where = hang, None
        if len(hang) + len(piece.rstrip()) > WIDTH and (block := _block(text, value, col)) is not None:
            if not cur.strip() or cur.strip() == head.strip():  # the part starts the line
                block[0].text = cur + block[0].text.lstrip()
            else:
                lines.append(Line(cur.rstrip(), where))
                block[0].text = hang + block[0].text.lstrip()
            lines.extend(block[:-1])
            cur, where = block[-1].text + piece[len(text):], block[-1].where
            first = False
            continue
        cur += piece
        where = where or _where(value)
        first = False
    lines.append(Line(cur.rstrip() + tail, where))
    return lines


def _block(text: str, value: Any, col: int) -> list[Line] | None:
    """A long ``key=value`` part over several lines at column ``col``, or None to keep it whole."""
    key = text[: len(text) - len(flat(value))] if "=" in text[:40] and text.endswith(flat(value)) else ""
    if isinstance(value, list) and value and all(isinstance(v, Call) for v in value):
        lines = [Line(" " * col + f"{key}[")]
        for v in value:
            lines.extend(call_lines(v, col + 4))
        return lines + [Line(" " * col + "]")]
    if isinstance(value, Call):
        return call_lines(value, col, key, "")
    if isinstance(value, list) and value:
        items = [(flat(v), v) for v in value]
        return _fill(key + "[", items, "]", col)
    if isinstance(value, dict) and value:
        lines = [Line(" " * col + key + "{")]
        for k, v in value.items():
            lines.extend(_fill(f"{py(k)}: ", [(flat(v), v)], ",", col + 4))
        return lines + [Line(" " * col + "}")]
    if isinstance(value, str) and "\n" in value.rstrip("\n"):
        chunks = value.splitlines(keepends=True)
        under = " " * (col + len(key))
        return [Line(" " * col + key + repr(chunks[0]))] + [Line(under + repr(c)) for c in chunks[1:]]
    return None


def call_lines(call: Call, indent: int, head: str = "", tail: str = ",") -> list[Line]:
    """The lines of a call at ``indent``: one line if it fits, else filled; children one per line."""
    one = " " * indent + head + flat(call) + tail
    if len(one) <= WIDTH and call.children is None:
        return [Line(one, _where(call))]
    parts = [(flat(a), a) for a in call.args] + [(f"{k}={flat(v)}", v) for k, v in kwargs_of(call).items() if k != call.children]
    if call.children is None:
        return _fill(f"{head}{call.fn}(", parts, ")" + tail, indent)
    kids = call.kwargs.get(call.children) or []
    lines = _fill(f"{head}{call.fn}(", parts + [(f"{call.children}=[", None)], "", indent)
    for kid in kids:
        lines.extend(_value_lines(kid, indent + 4))
    lines.append(Line(" " * indent + "])" + tail))
    return lines


def _value_lines(value: Any, indent: int) -> list[Line]:
    if isinstance(value, Call):
        return call_lines(value, indent)
    if isinstance(value, tuple) and len(value) == 2 and isinstance(value[1], list):  # a tab: (label, children)
        lines = [Line(" " * indent + f"({flat(value[0])}, [", _where(value[0]))]
        for kid in value[1]:
            lines.extend(_value_lines(kid, indent + 4))
        lines.append(Line(" " * indent + "]),"))
        return lines
    return [Line(" " * indent + flat(value) + ",", _where(value))]


def view_lines(view: list[Call]) -> list[Line]:
    """``VIEW = [...]``: the view's elements, one call (or nested block) each."""
    lines = [Line("VIEW = [")]
    for call in view:
        lines.extend(call_lines(call, 4))
    lines.append(Line("]"))
    return lines


def list_lines(head: str, items: list[Any], indent: int) -> list[Line]:
    """``head[item, ...]`` on one line if it fits, else one item per line."""
    one = " " * indent + head + "[" + ", ".join(flat(i) for i in items) + "]"
    if len(one) <= WIDTH:
        return [Line(one, _where(items))]
    if len(items) == 1 and isinstance(items[0], Call):
        return call_lines(items[0], indent, head + "[", "]")
    lines = [Line(" " * indent + head + "[")]
    for item in items:
        lines.extend(_value_lines(item, indent + 4))
    lines.append(Line(" " * indent + "]"))
    return lines


def method_lines(m: Method, indent: int = 4) -> list[Line]:
    """``def name(params):``, its docstring (if any) and its body, at ``indent``."""
    pad = " " * indent
    if m.raw:
        return [Line(pad + ln.text if ln.text else "", ln.where) for ln in m.lines]
    out = [Line(f"{pad}# {m.comment}")] if m.comment else []
    out.append(Line(f"{pad}def {m.name}({m.params}):"))
    body = pad + "    "
    if m.doc:
        out += [Line(body + d if d else "") for d in _doc_lines(m.doc)]
    lines = m.lines or ([] if m.doc else [Line("pass")])
    out += [Line(body + ln.text if ln.text else "", ln.where) for ln in lines]
    return out


def _doc_lines(doc: str) -> list[str]:
    doc = doc.replace('"""', "'''").replace("\\", "\\\\").strip()
    lines = doc.splitlines() or [""]
    if len(lines) == 1:
        return [f'"""{lines[0]}"""']
    return [f'"""{lines[0]}'] + [ln.rstrip() for ln in lines[1:]] + ['"""']


def declare_method(variables: list[Variable]) -> Method:
    """``_declare``: each variable's initial value in declaration order, its unit and doc as a comment."""
    lines: list[Line] = []
    for v in variables:
        note = ": ".join(x for x in (v.unit, v.doc) if x)
        init = list(v.init)
        if note and len(init) == 1 and len(init[0].text) + len(note) + 12 <= WIDTH:
            lines.append(Line(f"{init[0].text}  # {note}", init[0].where))
            continue
        if note:
            lines.append(Line(f"# {v.name}: {note}"))
        lines.extend(init)
    return Method("_declare", "self", "", lines)


def page_call(page: OdePlan) -> Call:
    """The runtime call that builds an ODE page inside ``_evolution``."""
    kw: dict[str, Any] = {"method": page.method, "step": page.step}
    if page.preliminary:
        kw["preliminary"] = Ref(page.preliminary, "self")
    if page.events:
        kw["events"] = [_event_call(e) for e in page.events]
    if page.tolerance != 1e-6:
        kw["tolerance"] = page.tolerance
    if page.max_step is not None:
        kw["max_step"] = page.max_step
    if not page.enabled:
        kw["enabled"] = False
    kw["where"] = page.where
    if page.events:
        kw["event_where"] = {e.name: e.where for e in page.events}
    rates = page.rates_method if isinstance(page.rates_method, Expr) else Ref(page.rates_method, "self")
    args = [Src("self"), page.title, page.independent]
    return Call("OdePage.of", args, {"states": list(page.rates), "rates": rates} | kw)


def _event_call(e: EventPlan) -> Call:
    action = Ref(e.action, "self") if e.action else None
    return Call("EventDef", [e.name, e.when, e.direction, action], {"stop": e.stop} if e.stop else {})


def module_calls(plan: AppPlan) -> list[Call]:
    """The runtime calls the app makes: its pages, the view, the programs and the settings."""
    pages = [page_call(p) if isinstance(p, OdePlan) else p for p in plan.pages]
    return pages + list(plan.view) + [program_call(p) for p in plan.programs] + [sim_call(plan), meta_call(plan)]


def program_call(p: Any) -> Call:
    return Call("ProgramDef", [], {"robot": p.robot, "q": p.q, "body": Ref(p.method), "gripper": p.gripper, "autostart": p.autostart, "where": p.where})


def sim_call(plan: AppPlan) -> Call:
    return Call("SimConfig", [], dict(plan.sim), keep=("fps",))


def meta_call(plan: AppPlan) -> Call:
    return Call("AppMeta", [], {"title": plan.title, "description": plan.description, "author": plan.author, "spec": plan.spec_name})


def used_names(texts: list[str]) -> set[str]:
    """The identifiers used in some Python source lines (to import only what the app uses)."""
    import io
    import tokenize

    names: set[str] = set()
    src = "\n".join(texts)
    try:
        for tok in tokenize.generate_tokens(io.StringIO(src).readline):
            if tok.type == tokenize.NAME:
                names.add(tok.string)
    except (tokenize.TokenError, SyntaxError):
        pass
    return names
