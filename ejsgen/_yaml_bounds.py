"""A YAML loader that refuses hostile documents while it composes them.

Two attacks cost little text and much time or memory:

- **Aliases that multiply** ("billion laughs"): ``a1: &a1 [*a0, *a0, ...]`` nine times
  over is 500 bytes that expand to 10^9 values. PyYAML composes aliases as shared nodes
  (cheap), but anything that walks the tree as values walks every copy.
  ``BoundedLoader`` keeps each composed node's expanded size (memoized, so counting is
  linear in the document) and stops at the alias that takes the values reached through
  aliases past ``MAX_ALIAS_VALUES``. An alias to a node that contains it (a cycle, which
  PyYAML accepts) is refused as well.
- **Deep nesting**: ``[[[[...]]]]`` 100,000 deep makes PyYAML's recursive composer (and
  every later tree walk) raise ``RecursionError``. Nesting deeper than ``MAX_DEPTH`` is
  refused at the first bracket or key past the bound.

Both raise ``HostileYaml`` with the PyYAML mark (0-based line and column) of the place.
"""

from __future__ import annotations

from typing import Any

import yaml
from yaml.events import AliasEvent, MappingStartEvent, SequenceStartEvent

__all__ = ["BoundedLoader", "HostileYaml", "MAX_ALIAS_VALUES", "MAX_DEPTH"]

MAX_DEPTH = 64
"""Deepest nesting of lists and mappings a spec may have (real specs stay under ~12)."""

MAX_ALIAS_VALUES = 100_000
"""Most values (scalars, lists, mappings) a document may reach through its aliases."""


class HostileYaml(Exception):
    """A document refused for its shape: ``mark`` (a PyYAML mark), ``message``, ``hint``."""

    def __init__(self, mark: Any, message: str, hint: str) -> None:
        super().__init__(message)
        self.mark = mark
        self.message = message
        self.hint = hint


class BoundedLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` with bounded nesting depth and bounded alias expansion."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0
        self._open: set[str] = set()  # anchors whose node is still being composed
        self._sizes: dict[int, int] = {}  # id(node) -> values in it, aliases expanded
        self._through_aliases = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(AliasEvent):
            event = self.peek_event()
            if event.anchor in self._open:
                raise HostileYaml(
                    event.start_mark,
                    f"the alias *{event.anchor} refers to the value that contains it (an endless loop)",
                    "copy the values out instead of using an alias inside its own anchor",
                )
            node = super().compose_node(parent, index)
            self._through_aliases += self._sizes.get(id(node), 1)
            if self._through_aliases > MAX_ALIAS_VALUES:
                raise HostileYaml(
                    event.start_mark,
                    f"the aliases up to *{event.anchor} expand the spec to more than "
                    f"{MAX_ALIAS_VALUES:,} values (a 'billion laughs' document?)",
                    "write the values out, or use fewer aliases of large anchors",
                )
            return node
        event = self.peek_event()
        nests = isinstance(event, (SequenceStartEvent, MappingStartEvent))
        if nests and self._depth >= MAX_DEPTH:
            raise HostileYaml(
                event.start_mark,
                f"the spec nests lists and mappings more than {MAX_DEPTH} levels deep here",
                "a spec needs a few levels; put deep data in a file listed under assets:",
            )
        anchor = event.anchor
        if anchor is not None:
            self._open.add(anchor)
        self._depth += nests
        try:
            node = super().compose_node(parent, index)
        finally:
            self._depth -= nests
            if anchor is not None:
                self._open.discard(anchor)
        self._sizes[id(node)] = 1 + sum(self._size_of(child) for child in _children(node))
        return node

    def _size_of(self, node: Any) -> int:
        return self._sizes.get(id(node), 1)


def _children(node: Any) -> list[Any]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []
