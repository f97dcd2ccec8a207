"""YAML mistakes are reported where the author has to fix them, in plain words.

Each case is a small YAML text with the mistake, the line:col an author must go to, and
words the message must (and PyYAML jargon it must not) contain. A robustness test then
damages every example spec many ways and checks the explanation never fails and always
points inside the file.
"""

from __future__ import annotations

import random
from pathlib import Path

import pytest
import yaml

from ejsgen._yaml_errors import explain
from ejsgen.errors import SpecError
from ejsgen.yamlload import load_yaml

JARGON = ("mapping values are not allowed", "<block end>", "<block mapping start>", "simple key", "flow node", "<stream end>")

CASES = [
    # (id, text, line, col, words in the message)
    ("bracket_never_closed_same_line", "a: {p: [1, 2, r: 1}\nb: 2\n", 1, 8, "this '[' is never closed"),
    ("bracket_never_closed_next_line", "a: [1, 2\nb: 2\n", 1, 4, "this '[' is never closed"),
    ("brace_never_closed", "a:\n  - s: {b: 1, c: 2\n  - t: 1\n", 2, 8, "this '{' is never closed"),
    ("double_quote_never_closed", 'a: {t: "x}\nb: 1\n', 1, 8, 'this " is never closed'),
    ("single_quote_never_closed", "a:\n  t: 'x\n  b: 1\n", 2, 6, "this ' is never closed"),
    ("quote_runs_on_to_a_later_quote", 'a:\n  t: "x\n  b: 1\n  c: "y"\n', 2, 6, "never closed on its line"),
    ("stray_closing_bracket", "a: [1, 2]]\n", 1, 10, "this ']' closes nothing"),
    ("hash_hides_the_rest_of_a_flow_line", "a: {color: #3366zz}\n", 1, 12, "'#3366zz' starts a YAML comment"),
    ("hash_leaves_a_key_without_value", "a:\n  color: #3366aa\n  b: 1\n", 2, 10, "so 'color' has no value"),
    ("indented_more_than_a_key_with_a_value", "a:\n  b: 1\n    c: 2\n", 3, 5, "indented more than the line above"),
    ("indented_between_levels", "a:\n  b: 1\n c: 2\n", 3, 2, "matches none of the lines above it"),
    ("list_item_beside_keys", "a:\n  - b: 1\n    - c: 2\n", 3, 5, "list item cannot stand"),
    ("key_after_list_items", "a:\n  - 1\n  b: 2\n", 3, 3, "a list cannot also hold keys"),
    ("colon_inside_a_plain_value", "label: Time: t\n", 1, 8, "contains ': '"),
    ("line_without_colon", "a:\n  b: 1\n  c\n  d: 2\n", 3, 3, "no ':' after 'c'"),
    ("odd_line_above_the_one_yaml_blames", "v:\n    - 1\n  - 2\n  - 3\n", 2, 5, "more than the lines around it"),
    ("tab_indent", "a:\n\tb: 1\n", 2, 1, "a tab character cannot indent YAML"),
    ("value_starting_with_at", "a: @x\n", 1, 4, "a value cannot start with '@'"),
    ("value_starting_with_star", "a: [1, *, 2]\n", 1, 8, "'*' at the start of a value marks an alias"),
    ("text_on_the_block_line", "a: | x\n", 1, 6, "after '|' or '>', the text starts on the next line"),
    ("list_item_after_a_key_on_its_line", "a: - b\n", 1, 4, "a '- ' item cannot stand here"),
]


@pytest.mark.parametrize("text,line,col,words", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_a_yaml_mistake_is_reported_where_it_is(text: str, line: int, col: int, words: str) -> None:
    with pytest.raises(SpecError) as info:
        load_yaml("lab.ejs.yaml", text=text)
    err = info.value
    assert (err.where.line, err.where.col) == (line, col), err.format()
    assert words in err.message
    assert not any(j in err.format() for j in JARGON), err.format()


@pytest.mark.parametrize("word", ["yes", "no", "on", "off", "On", "OFF"])
def test_yaml_1_1_boolean_words_stay_text(word: str) -> None:
    doc = load_yaml("lab.ejs.yaml", text=f"{word}: {word}\nlist: [{word}]\nflag: true\nother: False\n")
    assert doc.data == {word: word, "list": [word], "flag": True, "other": False}


def _damaged(text: str, r: random.Random) -> str:
    lines = text.split("\n")
    k = r.randrange(len(lines))
    line = lines[k]
    op = r.randrange(5)
    if op == 0:
        lines[k] = " " * r.randrange(1, 4) + line
    elif op == 1:
        lines[k] = line[r.randrange(1, 3):] if line.startswith(" ") else line
    elif op == 2 and line:
        j = r.randrange(len(line))
        lines[k] = line[:j] + r.choice("[]{}\"'#:,-|>&*!%@`") + line[j:]
    elif op == 3 and line:
        j = r.randrange(len(line))
        lines[k] = line[:j] + line[j + 1:]
    else:
        lines.insert(k, " " * r.randrange(0, 10) + r.choice(["x: 1", "- y", "z", '"a', "[b", "{c: d", "e: #f00"]))
    return "\n".join(lines)


def test_every_damaged_example_gets_an_explanation_inside_the_file() -> None:
    examples = sorted((Path(__file__).parents[2] / "examples").rglob("*.ejs.yaml"))
    assert examples
    r = random.Random(20261123)
    explained = 0
    for _ in range(400):
        text = _damaged(r.choice(examples).read_text(), r)
        try:
            list(yaml.compose_all(text, Loader=yaml.SafeLoader))
        except yaml.MarkedYAMLError as exc:
            why = explain(exc, text)  # must not raise
            n_lines = len(text.split("\n"))
            assert 1 <= why.line <= n_lines + 1 and why.col >= 1, (why, text)
            assert why.message and not any(j in why.message for j in JARGON), why
            explained += 1
    assert explained > 100
