"""Read a ``.ejs.yaml`` file into plain Python values, keeping where every node stands.

``load_yaml`` returns a ``Document``: ``data`` (dicts, lists, scalars) and ``positions``,
a map from a node's path (a tuple of mapping keys and list indices) to its 1-based line
and column, plus for every string scalar where its *text* starts (so code snippets can
point at their own lines and columns in the spec).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from ejsgen._yaml_bounds import BoundedLoader, HostileYaml
from ejsgen._yaml_errors import Explained, explain
from ejsgen.errors import Location, SpecError

__all__ = ["Document", "TextOrigin", "load_yaml", "Path_"]

Path_ = tuple[Any, ...]


@dataclass(frozen=True)
class TextOrigin:
    """Where a string scalar's text starts: ``line``/``col`` (1-based) of its first character.

    ``block``: a literal/folded block (``|``/``>``), whose text lines are the file's lines
    one for one, all starting at ``col``; otherwise the text is on one line (quoted or
    plain) and later lines, if any, are approximate.
    """

    line: int
    col: int
    block: bool


@dataclass
class Document:
    """A loaded spec: ``data``, node ``positions``, string ``origins``, and the ``file`` name."""

    file: str
    data: Any
    positions: dict[Path_, tuple[int, int]] = field(default_factory=dict)
    origins: dict[Path_, TextOrigin] = field(default_factory=dict)

    def loc(self, path: Path_) -> Location:
        """The location of the node at ``path``, or of its nearest ancestor that has one."""
        p = tuple(path)
        while p and p not in self.positions:
            p = p[:-1]
        line, col = self.positions.get(p, (1, 1))
        return Location(self.file, line, col)

    def key_loc(self, path: Path_) -> Location:
        """The location of the *key* of the mapping entry at ``path`` (falls back to ``loc``)."""
        key = ("__key__",) + tuple(path)
        if key in self.positions:
            line, col = self.positions[key]
            return Location(self.file, line, col)
        return self.loc(path)


class _Builder:
    def __init__(self, file: str, text: str) -> None:
        self.file = file
        self.lines = text.splitlines()
        self.positions: dict[Path_, tuple[int, int]] = {}
        self.origins: dict[Path_, TextOrigin] = {}

    def error(self, mark: Any, message: str, hint: str = "") -> SpecError:
        return SpecError(Location(self.file, mark.line + 1, mark.column + 1), message, hint)

    def build(self, node: yaml.Node, path: Path_) -> Any:
        self.positions[path] = (node.start_mark.line + 1, node.start_mark.column + 1)
        if isinstance(node, yaml.MappingNode):
            out: dict[str, Any] = {}
            for key_node, value_node in node.value:
                if not isinstance(key_node, yaml.ScalarNode):
                    raise self.error(key_node.start_mark, "a key must be a plain name")
                if key_node.tag == "tag:yaml.org,2002:merge":
                    raise self.error(key_node.start_mark, "YAML merge keys ('<<') are not supported in specs")
                key = str(key_node.value)
                if key in out:
                    raise self.error(key_node.start_mark, f"duplicate key '{key}'")
                self.positions[("__key__",) + path + (key,)] = (key_node.start_mark.line + 1, key_node.start_mark.column + 1)
                self._check_hidden_value(key, key_node, value_node)
                out[key] = self.build(value_node, path + (key,))
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, path + (i,)) for i, item in enumerate(node.value)]
        assert isinstance(node, yaml.ScalarNode)
        value = yaml.SafeLoader.construct_scalar(_LOADER, node)  # raw text
        try:
            resolved = _resolve(node)
        except _AmbiguousNumber as exc:
            raise self.error(node.start_mark, exc.message, exc.hint) from None
        if isinstance(resolved, str):
            self.origins[path] = self._origin(node)
            return value
        return resolved

    def _check_hidden_value(self, key: str, key_node: yaml.Node, value_node: yaml.Node) -> None:
        """Refuse ``key: #3366aa``: the '#' starts a comment, so the key silently has no value."""
        if not (isinstance(value_node, yaml.ScalarNode) and value_node.tag == "tag:yaml.org,2002:null" and value_node.value == ""):
            return
        line = self.lines[key_node.end_mark.line] if key_node.end_mark.line < len(self.lines) else ""
        m = _HIDDEN_VALUE.match(line, key_node.end_mark.column)
        if m:
            word = m.group(2)
            raise SpecError(
                Location(self.file, key_node.end_mark.line + 1, m.start(2) + 1),
                f"'{word}' starts a YAML comment here, so '{key}' has no value",
                f'write text that starts with \'#\' in quotes, e.g. {key}: "{word}"',
            )

    def _origin(self, node: yaml.ScalarNode) -> TextOrigin:
        line, col = node.start_mark.line, node.start_mark.column
        if node.style in ("|", ">"):
            indent = None
            for i in range(line + 1, min(len(self.lines), node.end_mark.line + 1)):
                src = self.lines[i]
                if src.strip():
                    indent = len(src) - len(src.lstrip(" "))
                    break
            return TextOrigin(line + 2, (indent or 0) + 1, True)
        if node.style in ("'", '"'):
            return TextOrigin(line + 1, col + 2, False)
        return TextOrigin(line + 1, col + 1, False)


_LOADER = yaml.SafeLoader("")
_HIDDEN_VALUE = re.compile(r"(\s*:[ \t]+)(#[0-9A-Za-z]{3,8})\b")


_BOOL_WORDS = ("true", "false")


def _resolve(node: yaml.ScalarNode) -> Any:
    """The value of a scalar, by YAML 1.2's rules for booleans.

    YAML 1.1 (PyYAML's default) also reads ``yes``/``no``/``on``/``off`` as booleans, so a
    dropdown option ``off`` or a value ``on`` would silently become ``False``/``True``; in a
    spec, as in YAML 1.2, only ``true`` and ``false`` are booleans and those words are text.
    """
    number = _number_12(node)
    if number is not _NOT_A_NUMBER:
        return number
    if node.tag == "tag:yaml.org,2002:str":
        return str(node.value)
    if node.tag == "tag:yaml.org,2002:bool" and node.value.lower() not in _BOOL_WORDS:
        return str(node.value)
    try:
        return _LOADER.construct_object(node, deep=True)
    except yaml.YAMLError:
        return str(node.value)


# -- numbers, by YAML 1.2's core schema --------------------------------------------------------------

_NOT_A_NUMBER = object()
_NUMERIC_TAGS = ("tag:yaml.org,2002:str", "tag:yaml.org,2002:int", "tag:yaml.org,2002:float")
_DIGITS = r"[0-9]+(?:_[0-9]+)*"  # digit groups as Python writes them: 1_000_000
_INT_12 = re.compile(rf"[-+]?{_DIGITS}\Z")
_RADIX_INT = re.compile(r"[-+]?0(?:o[0-7]+|x[0-9a-fA-F]+|b[01]+)\Z")
_FLOAT_12 = re.compile(rf"[-+]?(?:\.{_DIGITS}|{_DIGITS}(?:\.(?:{_DIGITS})?)?)(?:[eE][-+]?[0-9]+)?\Z")
_INF_12 = re.compile(r"([-+]?)\.(?:inf|Inf|INF)\Z")
_NAN_12 = re.compile(r"\.(?:nan|NaN|NAN)\Z")
_LEADING_ZERO = re.compile(r"[-+]?0[0-9_]+\Z")


class _AmbiguousNumber(Exception):
    """A plain scalar whose number YAML 1.1 and 1.2 read differently (``010``: 8 or 10)."""

    def __init__(self, message: str, hint: str) -> None:
        super().__init__(message)
        self.message, self.hint = message, hint


def _number_12(node: yaml.ScalarNode) -> Any:
    """The number a plain, untagged scalar is by YAML 1.2's core schema, else ``_NOT_A_NUMBER``.

    YAML 1.1 (PyYAML's default) needs a dot and a signed exponent (``1.0e+3``), so ``1e5``,
    ``1E-3`` and ``3e8`` would silently be text; by YAML 1.2 they are floats, parsed as
    Python's ``float`` parses them. Also floats: ``.5``, ``1.``, ``+1.0e3``, ``.inf``,
    ``-.inf``, ``.nan``; ints: ``42``, ``-7``, ``0x1F``, ``0o17``, and (as PyYAML and
    Python read them, so that no spec changes meaning) ``0b101`` and digit groups
    ``1_000``. YAML 1.1's base-60 numbers (``1:30`` was 90) are text, as in YAML 1.2. An
    int with a leading zero (``010``: 8 by YAML 1.1, 10 by YAML 1.2) raises
    ``_AmbiguousNumber``. Quoted and explicitly tagged scalars (``!!str 1e5``) are left alone.
    """
    if node.style is not None or node.tag not in _NUMERIC_TAGS:
        return _NOT_A_NUMBER
    text = node.value
    if node.end_mark.index - node.start_mark.index != len(text):
        return _NOT_A_NUMBER  # a tag or an anchor before it, or spread over lines: not a plain number
    if _LEADING_ZERO.match(text):
        digits = text.lstrip("+-").lstrip("0_") or "0"
        raise _AmbiguousNumber(
            f"'{text}' is ambiguous: an int with a leading zero is octal in YAML 1.1 and decimal in YAML 1.2",
            f"write {text[0] if text[0] in '+-' else ''}{digits} for the decimal number, "
            f"0o{text.lstrip('+-').lstrip('0_') or '0'} for an octal one, or \"{text}\" for text",
        )
    if _INT_12.match(text) or _RADIX_INT.match(text):
        return int(text, 0) if _RADIX_INT.match(text) else int(text)
    if _FLOAT_12.match(text):
        return float(text)
    m = _INF_12.match(text)
    if m:
        return float(f"{m.group(1)}inf")
    if _NAN_12.match(text):
        return float("nan")
    if node.tag != "tag:yaml.org,2002:str":
        return str(text)  # a YAML 1.1-only number (base 60, odd underscores): text, as in YAML 1.2
    return _NOT_A_NUMBER


def load_yaml(path: str | Path, *, text: str | None = None, display_name: str | None = None) -> Document:
    """Load a spec file (or ``text``) keeping positions; raises ``SpecError`` on YAML errors."""
    p = Path(path)
    name = display_name or str(path)
    if text is None:
        try:
            text = p.read_text(encoding="utf-8")
        except FileNotFoundError:
            raise SpecError(Location(name, 1, 1), "no such file") from None
        except UnicodeDecodeError as exc:
            raise SpecError(Location(name, 1, 1), f"the file is not UTF-8 text ({exc.reason})") from None
    builder = _Builder(name, text)
    try:
        nodes = list(yaml.compose_all(text, Loader=BoundedLoader))
    except HostileYaml as exc:
        raise SpecError(Location(name, exc.mark.line + 1, exc.mark.column + 1), exc.message, exc.hint) from None
    except yaml.MarkedYAMLError as exc:
        try:
            why = explain(exc, text)
        except Exception:  # an explanation must never hide the error itself
            mark = exc.problem_mark or exc.context_mark
            why = Explained(mark.line + 1 if mark else 1, mark.column + 1 if mark else 1, f"invalid YAML: {exc.problem or exc}")
        raise SpecError(Location(name, why.line, why.col), why.message, why.hint) from None
    except yaml.YAMLError as exc:
        raise SpecError(Location(name, 1, 1), f"invalid YAML: {exc}") from None
    if len(nodes) != 1 or nodes[0] is None:
        raise SpecError(Location(name, 1, 1), "a spec is one YAML document (a mapping with 'ejs', 'title', 'model', 'view')")
    data = builder.build(nodes[0], ())
    return Document(name, data, builder.positions, builder.origins)
