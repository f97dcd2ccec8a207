"""The ``console`` element in the control panel: what the simulation's code printed.

The lines come from the :class:`~ejsrl.sim._console.ConsoleLog` of the panel's app (one
simulation: one browser tab, or every tab with ``--shared``), so a tab shows only its own
prints. Each line is escaped (``html.escape``) before it reaches the page: a printed
``<b>`` or ``<img onerror=...>`` shows as those characters. The box scrolls and starts at
its newest line (a column laid out from the bottom, no script); the Clear button empties
this simulation's log.
"""

from __future__ import annotations

import html
from typing import Any

from ejsrl.sim._console import ConsoleLog, console_log
from ejsrl.view._wire import set_prop
from ejsrl.view.elements_text import Console

__all__ = ["ConsoleBinding", "console_html"]

_BOX = ('<div class="ejs-console" style="height:{height}px;overflow-y:auto;display:flex;flex-direction:column-reverse;'
        'border:1px solid #ced4da;border-radius:4px;padding:4px 6px;font-family:monospace;font-size:0.75rem;'
        'line-height:1.35;white-space:pre-wrap;word-break:break-word"><div>{body}</div></div>')
_LABEL = '<div style="font-size:0.8rem;font-weight:600;margin:2px 0">{}</div>'
_EMPTY = '<span style="opacity:0.55">(nothing printed yet)</span>'


def console_html(label: str, lines: list[str], height: int) -> str:
    """The console's HTML: ``label`` over a box ``height`` pixels high holding ``lines``, escaped."""
    body = "\n".join(html.escape(line) for line in lines) if lines else _EMPTY
    return (_LABEL.format(html.escape(label)) if label else "") + _BOX.format(height=int(height), body=body)


class ConsoleBinding:
    """One ``console`` element of one panel and its viser handles (the box and the Clear button)."""

    def __init__(self, gui: Any, console: Console, app: Any) -> None:
        self.console = console
        self.app = app
        self.log: ConsoleLog = console_log(app)
        self.revision = self.log.revision
        self.shown = self._html()
        self.handle = gui.add_html(self.shown)
        self.clear_button = gui.add_button(f"Clear {console.label.lower()}" if console.label else "Clear")

        @self.clear_button.on_click
        def _(_event: Any) -> None:
            with app.lock:
                self.log.clear()
                self.refresh()

    def _html(self) -> str:
        return console_html(self.console.label, self.log.lines(self.console.lines), self.console.height)

    def refresh(self, value_of: Any = None) -> None:
        """Show the lines printed since the last call, if any (the caller holds the model lock).
        ``value_of`` is unused: every panel binding of text is refreshed the same way."""
        revision = self.log.revision
        if revision == self.revision:
            return
        self.revision = revision
        text = self._html()
        if text != self.shown:
            set_prop(self.handle, "content", text)
            self.shown = text
