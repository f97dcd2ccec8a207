"""Explain PyYAML's errors in plain words, at the place the author has to change.

PyYAML reports where its parser *noticed* a problem, in its own terms ("mapping values are
not allowed here", "expected <block end>, but found '<block mapping start>'"). Authors need
where the problem *is*: the '[' or quote that is never closed, the line indented one step
too far, the '#' that turned the rest of a line into a comment. ``explain`` looks at the
error, the tokens before it and the lines around it, and returns that place and a message.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import yaml

from ejsgen._yaml_bounds import BoundedLoader, HostileYaml

__all__ = ["Explained", "explain"]

_CLOSER = {"[": "]", "{": "}"}


@dataclass(frozen=True)
class Explained:
    """A YAML problem: 1-based ``line``/``col``, ``message`` and ``hint`` (may be empty)."""

    line: int
    col: int
    message: str
    hint: str = ""


def explain(exc: yaml.MarkedYAMLError, text: str) -> Explained:
    """The place and plain-words message for a PyYAML error in ``text``."""
    lines = text.splitlines()
    mark = exc.problem_mark or exc.context_mark
    problem = exc.problem or ""
    context = exc.context or ""
    pline, pcol = (mark.line, mark.column) if mark else (0, 0)
    if "found character '\\t'" in problem:
        return Explained(pline + 1, pcol + 1, "invalid YAML: a tab character cannot indent YAML; use spaces")
    if context == "while scanning a quoted scalar" and exc.context_mark is not None:
        return _unclosed_quote(exc.context_mark.line, exc.context_mark.column, lines)
    tokens = _tokens_before(text, mark.index if mark else len(text))
    quoted = _runaway_quote(tokens, pline)
    if quoted is not None:
        return quoted
    opener = _unclosed_opener(tokens)
    if opener is not None:
        found = _explain_opener(opener, lines, pline, pcol, problem)
        if found is not None:
            return found
    stray = re.search(r"found '([\]}])'", problem)
    if stray:
        return Explained(pline + 1, pcol + 1, f"this '{stray.group(1)}' closes nothing", "remove it, or add the '[' or '{' it should close")
    if problem == "mapping values are not allowed here":
        return _odd_line_above(lines, pline) or _colon_in_value(lines, pline, pcol)
    if context.startswith("while parsing a block") and problem.startswith("expected <block end>"):
        return _odd_line_above(lines, pline) or _misindented(lines, pline)
    if "could not find expected ':'" in problem and exc.context_mark is not None:
        cm = exc.context_mark
        word = _line(lines, cm.line)[cm.column:].split(" #")[0].strip()
        return Explained(
            cm.line + 1,
            cm.column + 1,
            f"this line is neither 'name: value' nor a '- ' item (no ':' after '{word}')",
            "add the ':', or indent the line to continue the text above it, or write long text in a '|' block",
        )
    if "did not find expected '-' indicator" in problem or "did not find expected key" in problem:
        return _misindented(lines, pline)
    if "expected '<document start>'" in problem:
        return Explained(pline + 1, pcol + 1, "this line does not belong to the spec's top-level mapping", "top-level keys start at column 1 and end with ':'")
    flow = re.match(r"expected ',' or '([\]}])', but got '(.*)'$", problem)
    if flow:
        close = flow.group(1)
        got = "text" if flow.group(2).startswith("<") else f"'{flow.group(2)}'"
        return Explained(
            pline + 1,
            pcol + 1,
            f"inside {'{...}' if close == '}' else '[...]'}, {got} cannot follow the value before it without a ','",
            "text with [ ] { } , : or # inside {...} or [...] must be quoted, e.g. bind: \"q[2]\"",
        )
    special = _special_start(exc, lines)
    if special is not None:
        return special
    return Explained(pline + 1, pcol + 1, f"invalid YAML: {problem or 'cannot read this'}")


_MEANING = {"&": "an anchor", "*": "an alias", "!": "a tag", "|": "a block of text", ">": "a folded block of text"}


def _special_start(exc: yaml.MarkedYAMLError, lines: list[str]) -> Explained | None:
    """Text starting with a character YAML gives a meaning (``* & ! | > @ ` %``) or stray."""
    problem = exc.problem or ""
    m = exc.problem_mark
    if m is None:
        return None
    if "that cannot start any token" in problem or problem.startswith("expected the node content"):
        ch = _line(lines, m.line)[m.column : m.column + 1]
        return Explained(m.line + 1, m.column + 1, f"a value cannot start with '{ch}' in YAML", "put the text in quotes")
    cm = exc.context_mark
    if cm is not None and (problem.startswith("expected alphabetic or numeric character") or problem.startswith("expected URI") or "alias" in problem):
        ch = _line(lines, cm.line)[cm.column : cm.column + 1]
        return Explained(cm.line + 1, cm.column + 1, f"'{ch}' at the start of a value marks {_MEANING.get(ch, 'YAML syntax')}", f"put text that starts with '{ch}' in quotes")
    if "undefined alias" in problem:
        return Explained(m.line + 1, m.column + 1, "'*' at the start of a value marks an alias", "put text that starts with '*' in quotes")
    if problem.startswith("expected a comment or a line break") or problem.startswith("expected chomping or indentation"):
        return Explained(m.line + 1, m.column + 1, "after '|' or '>', the text starts on the next line, indented", "move this text to its own line below")
    if problem == "sequence entries are not allowed here":
        return Explained(m.line + 1, m.column + 1, "a '- ' item cannot stand here", "start a list item on its own line, indented under its key")
    return None


def _spaces(n: int) -> str:
    return f"{n} space" if n == 1 else f"{n} spaces"


def _line(lines: list[str], i: int) -> str:
    return lines[i] if 0 <= i < len(lines) else ""


def _tokens_before(text: str, index: int) -> list[yaml.Token]:
    """The scanner's tokens that start before ``index`` (as far as the scanner gets)."""
    out: list[yaml.Token] = []
    try:
        for tok in yaml.scan(text, Loader=yaml.SafeLoader):
            if tok.start_mark.index >= index:
                break
            out.append(tok)
    except yaml.YAMLError:
        pass
    return out


def _unclosed_quote(line: int, col: int, lines: list[str]) -> Explained:
    quote = _line(lines, line)[col : col + 1] or '"'
    return Explained(
        line + 1,
        col + 1,
        f"this {quote} is never closed",
        f"end the text with {quote} on the same line (for text over several lines, use a '|' block)",
    )


def _runaway_quote(tokens: list[yaml.Token], pline: int) -> Explained | None:
    """A quoted text that runs over lines up to the error: its closing quote is missing."""
    for tok in reversed(tokens):
        if isinstance(tok, yaml.ScalarToken) and tok.style in ('"', "'") and tok.start_mark.line != tok.end_mark.line:
            if tok.end_mark.line >= pline - 1:
                s = tok.start_mark
                return Explained(
                    s.line + 1,
                    s.column + 1,
                    f"this {tok.style} is never closed on its line (the text runs on to line {tok.end_mark.line + 1})",
                    f"end the text with {tok.style} on the same line (for text over several lines, use a '|' block)",
                )
            return None
    return None


def _unclosed_opener(tokens: list[yaml.Token]) -> yaml.Token | None:
    """The innermost '[' or '{' still open after ``tokens``."""
    stack: list[yaml.Token] = []
    for tok in tokens:
        if isinstance(tok, (yaml.FlowSequenceStartToken, yaml.FlowMappingStartToken)):
            stack.append(tok)
        elif isinstance(tok, (yaml.FlowSequenceEndToken, yaml.FlowMappingEndToken)) and stack:
            stack.pop()
    return stack[-1] if stack else None


def _comment_start(line: str, start: int) -> int | None:
    """The column of a '#' that starts a comment in ``line`` after ``start`` (outside quotes)."""
    quote = ""
    for i in range(start, len(line)):
        ch = line[i]
        if quote:
            if ch == quote:
                quote = ""
        elif ch in "\"'" and (i == 0 or line[i - 1] in " \t[{,:"):
            quote = ch
        elif ch == "#" and i > 0 and line[i - 1] in " \t":
            return i
    return None


def _explain_opener(opener: yaml.Token, lines: list[str], pline: int, pcol: int, problem: str) -> Explained | None:
    s = opener.start_mark
    src = _line(lines, s.line)
    ch = src[s.column : s.column + 1] or "["
    close = _CLOSER.get(ch, "]")
    hash_col = _comment_start(src, s.column + 1)
    if hash_col is not None:
        word = src[hash_col:].split(",")[0].split("}")[0].split("]")[0].strip()
        key = re.search(r"([A-Za-z_][\w]*)\s*:\s*$", src[:hash_col])
        example = f'{key.group(1)}: "{word}"' if key else f'"{word}"'
        return Explained(
            s.line + 1,
            hash_col + 1,
            f"'{word}' starts a YAML comment, which hides the rest of the line, so the '{ch}' at column {s.column + 1} is never closed",
            f"write text that starts with '#' in quotes, e.g. {example}",
        )
    mismatched = re.search(r"but got '([\]}])'", problem)
    later = pline > s.line
    if later or (mismatched and mismatched.group(1) != close) or "<stream end>" in problem or "end of stream" in problem:
        return Explained(
            s.line + 1,
            s.column + 1,
            f"this '{ch}' is never closed",
            f"add the missing '{close}'" + (" on this line" if later else ""),
        )
    return None


def _indent(text: str) -> int:
    return len(text) - len(text.lstrip(" "))


def _key_col(text: str) -> int:
    """Where the content of a line starts after its indentation and any '- ' markers."""
    i = _indent(text)
    while text[i : i + 2] == "- " or text[i:] == "-":
        i += 2
        while i < len(text) and text[i] == " ":
            i += 1
    return i


def _content_lines_before(lines: list[str], i: int) -> list[int]:
    return [j for j in range(min(i, len(lines)) - 1, -1, -1) if lines[j].strip() and not lines[j].lstrip().startswith("#")]


def _key_of(text: str) -> str:
    m = re.match(r"\s*(?:-\s+)*([^\s:#][^:#]*?)\s*:(\s|$)", text)
    return m.group(1) if m else text.strip()[:20]


def _colon_in_value(lines: list[str], pline: int, pcol: int) -> Explained:
    """PyYAML's 'mapping values are not allowed here': a line indented too far, or ': ' in a value."""
    src = _line(lines, pline)
    before = _content_lines_before(lines, pline)
    head = src[_key_col(src) : pcol]
    if ": " not in head and before:
        prev = lines[before[0]]
        if _indent(src) > _indent(prev):
            prev_key = _key_of(prev)
            return Explained(
                pline + 1,
                _indent(src) + 1,
                f"this line is indented more than the line above it, so it reads as more of the value of '{prev_key}'",
                f"indent '{_key_of(src)}' by {_spaces(_key_col(prev))}, like '{prev_key}', to make it a key beside it",
            )
    m = re.match(r"(\s*(?:-\s+)*[^\s:#][^:#]*?\s*:\s+)(.*)$", src)
    col = len(m.group(1)) if m else pcol
    value = (m.group(2) if m else src[col:]).split(" #")[0].rstrip()
    key = _key_of(src)
    return Explained(
        pline + 1,
        col + 1,
        f"the value of '{key}' contains ': ', which YAML reads as the start of another key",
        f"put the text in quotes: {key}: \"{value}\"",
    )


def _parses_past(lines: list[str], line: int) -> bool:
    """Whether ``lines`` parse as YAML, or at least up to and including ``line`` (0-based)."""
    try:
        list(yaml.compose_all("\n".join(lines), Loader=BoundedLoader))
    except HostileYaml:
        return False
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        return mark is not None and mark.line > line
    except yaml.YAMLError:
        return False
    return True


def _starts_nodes(lines: list[str], at: list[int]) -> bool:
    """Whether a YAML token starts at the first character of each line in ``at`` (0-based).

    A line that YAML reads as more of the text above it (a plain or block scalar running
    on) starts no token: re-indenting a line so that its neighbours become text is no fix.
    """
    starts = set()
    try:
        for tok in yaml.scan("\n".join(lines), Loader=yaml.SafeLoader):
            starts.add((tok.start_mark.line, tok.start_mark.column))
    except yaml.YAMLError:
        pass
    return all((j, _indent(lines[j])) in starts for j in at)


def _odd_line_above(lines: list[str], pline: int) -> Explained | None:
    """The line above the error, when it alone is misindented and its neighbours agree.

    PyYAML notices a wrong indentation one line late: after a line indented one step too
    far, it is the next, correct line that does not fit. If that next line's indentation
    is shared by a neighbour (the line after it or the one before the line above), and
    re-indenting the line above makes the file read past the error with every line still
    starting its own node, the line above is the one to fix.
    """
    before = _content_lines_before(lines, pline)
    if not before or not lines[pline].strip():
        return None
    p = before[0]
    after = [j for j in range(pline + 1, len(lines)) if lines[j].strip() and not lines[j].lstrip().startswith("#")]
    upto = after[0] if after else pline
    neighbours = [_indent(lines[j]) for j in (*after[:1], *before[1:2])]
    if _indent(lines[pline]) not in neighbours:
        return None  # no second line agrees with the one where YAML noticed: no odd one out
    targets = [_indent(lines[pline])] + ([_indent(lines[before[1]])] if len(before) > 1 else [])
    for target in dict.fromkeys(targets):
        if target == _indent(lines[p]):
            continue
        trial = list(lines)
        trial[p] = " " * target + lines[p].lstrip(" ")
        if _parses_past(trial, upto) and _starts_nodes(trial, [pline, *after[:1]]):
            more = _indent(lines[p]) > target
            like = pline if target == _indent(lines[pline]) else before[1]
            return Explained(
                p + 1,
                _indent(lines[p]) + 1,
                f"this line is indented by {_spaces(_indent(lines[p]))}, {'more' if more else 'less'} than the lines around it",
                f"indent it by {_spaces(target)}, like line {like + 1}",
            )
    return None


def _misindented(lines: list[str], pline: int) -> Explained:
    """A line whose indentation fits none of the structure above it."""
    src = _line(lines, pline)
    ind = _indent(src)
    before = _content_lines_before(lines, pline)
    if not before:
        return Explained(pline + 1, ind + 1, "this line is indented, but nothing above it holds it", "start top-level keys at column 1")
    prev = lines[before[0]]
    levels: dict[int, int] = {}  # column -> line (0-based) of the lines that enclose the previous one
    limit = None
    for j in before:
        t = lines[j]
        if limit is None or _indent(t) < limit:
            levels.setdefault(_key_col(t), j)
            levels.setdefault(_indent(t), j)
            limit = _indent(t)
    cols = sorted(levels)
    is_item = src.lstrip().startswith("- ") or src.strip() == "-"
    if ind > _key_col(prev) or (ind > _indent(prev) and not is_item):
        prev_key = _key_of(prev)
        return Explained(
            pline + 1,
            ind + 1,
            f"this line is indented more than the line above it, but '{prev_key}' (line {before[0] + 1}) already has its value",
            f"indent it by {_spaces(_key_col(prev))}, like '{prev_key}', or put it under a key that ends with ':'",
        )
    if ind not in cols:
        near = [c for c in (max((c for c in cols if c < ind), default=None), min((c for c in cols if c > ind), default=None)) if c is not None]
        where = " or ".join(f"{_spaces(c)} as on line {levels[c] + 1}" for c in near)
        return Explained(
            pline + 1,
            ind + 1,
            f"this line is indented by {_spaces(ind)}, which matches none of the lines above it ({where})",
            "indent it exactly like the line it belongs beside",
        )
    if is_item:
        return Explained(
            pline + 1,
            ind + 1,
            "this '- ' item is indented like the keys above it, where a list item cannot stand",
            "to give a key a list, end the key's line with ':' and indent the items under it",
        )
    return Explained(
        pline + 1,
        ind + 1,
        "this key is indented like the '- ' items above it, but a list cannot also hold keys",
        "start it with '- ' to make it an item, or indent it like the key that holds the list",
    )
