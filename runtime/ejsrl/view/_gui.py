"""The control panel: builds viser GUI handles from the view's elements and refreshes them.

:class:`Panel` walks the element list once (folders, tabs, markdown, labels, controls,
buttons, plots, images) and keeps one small binding per dynamic element. Each frame
:meth:`Panel.refresh` reads the model (the caller holds the model lock) and sends only
the values that changed. Values coming back from the browser are validated by
:func:`ejsrl.view._validate.validate_control` before the app applies them.
"""

from __future__ import annotations

import logging
import math
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ejsrl.view._image import picture_of
from ejsrl.view._plots import ImageBinding, PlotBinding
from ejsrl.view._validate import option_label, validate_control
from ejsrl.view._wire import set_markdown
from ejsrl.view.elements import (
    Button,
    Checkbox,
    Control,
    Drawing,
    Dropdown,
    Dynamic,
    Folder,
    Image,
    Label,
    Markdown,
    Number,
    Plot,
    Scene,
    SceneKeys,
    Slider,
    Tabs,
    Text,
    is_dynamic,
    keep_spaces,
)
from ejsrl.view.elements_text import Console, Table

__all__ = ["Panel", "ControlBinding", "USER_HOLD_SECONDS"]

log = logging.getLogger("ejsrl.view")

#: after the user changes a control, the model's value is not pushed back to it for this long
USER_HOLD_SECONDS = 0.6

#: ``notify(client or None, title, body, color)`` -> the notification handles it made
Notify = Callable[[Any, str, str, str], list]


def _finite(x: Any) -> bool:
    try:
        return math.isfinite(float(x))
    except (TypeError, ValueError):
        return False


_UNSET = object()


#: the panel's width (pixels) when the spec sets none: room for plots and images ...
PANEL_WIDTH = 400
#: the width (pixels) of the About panel, docked at the left edge
ABOUT_WIDTH = 300
#: ... and for the title in the panel's header (pixels per character, and the header's icons)
_TITLE_PX_PER_CHAR = 7.0
_HEADER_PX = 130

#: Fixes to viser's page, sent once with the panel (HTML the app writes, never user text):
#: arrow keys pressed on a focused slider move the slider only (viser's keyboard camera
#: controls skip inputs but not sliders, so the 3D view turned as well); the panel's title
#: wraps instead of being cut short.
CLIENT_TWEAKS = (
    "<style>.ejs-tweaks{display:none}</style>"
    '<img class="ejs-tweaks" alt="" src="data:," onerror="'
    "if(!window.__ejsKeys){window.__ejsKeys=1;document.body.addEventListener('keydown',function(e){"
    "var t=e.target;if(/^Arrow/.test(e.key)&amp;&amp;t&amp;&amp;t.closest&amp;&amp;t.closest('[role=slider]'))e.stopPropagation();});}"
    '">'
)


#: A lab without a ``scene`` gives the window to its panel, as EJS shows only the panels an
#: author declares: the panel asks for more than any window (the client keeps its least
#: 3D view, 120 px, and gives the panel the rest), holds the About text itself, and the
#: empty 3D view (and its axes gizmo) are hidden.
NO_SCENE_WIDTH = 100_000.0
#: Notifications (an error's, the browser's) go to the bottom-left corner there: at the top-left
#: they covered the left part of the panel's error box and of its controls.
NO_SCENE_TWEAKS = ('<style>div[style*="inset"]:has(canvas[data-engine]){visibility:hidden}'
                   ".mantine-Notifications-root{top:auto!important;bottom:1em!important}</style>")
#: the height (pixels) of a plot in a panel that has the window (else the panel's width / 1.6)
NO_SCENE_PLOT_HEIGHT = 300


def has_scene(elements: Any) -> bool:
    """Whether a view (a list of elements, with folders and tabs) holds a 3D ``Scene``."""
    for el in elements or ():
        if isinstance(el, Scene):
            return True
        if isinstance(el, Folder) and has_scene(el.children):
            return True
        if isinstance(el, Tabs) and any(has_scene(children) for _label, children in el.tabs):
            return True
    return False


#: below this measured speed (1.0: as fast as the lab asks) the readout says the server (or, in a web page, the browser) is busy
SLOW_SPEED = 0.95
#: below this many frames a second shown to a tab (classroom serving: ``app.shown_fps``,
#: set by :mod:`ejsrl.app._sessions`), or below SLOW_SPEED of the lab's own ``fps`` when it
#: asks for fewer, the readout says so too (a lab at ``fps: 10`` showing 10 is not held back)
SLOW_SHOWN_FPS = 20.0
#: who is too busy when the readout says so: a web page (``ejsgen build --web``) runs the lab in
#: the student's browser, with no server
BUSY = "the browser is busy" if sys.platform in ("wasi", "emscripten") else "the server is busy"


def slow_text(speed: float, realtime: bool) -> str:
    """What the time readout adds when the server cannot keep up (``speed`` < :data:`SLOW_SPEED`)."""
    if realtime:
        return f" · *running at {speed:.0%} of real time ({BUSY})*"
    return f" · *running at {speed:.0%} speed ({BUSY})*"


def shown_digits(*values: float | None) -> int:
    """The decimals a number box shows: enough for each of ``values`` (a control's min, max
    and step, not its initial value) to be written exactly, at most 7 (as viser)."""
    digits = 0
    for v in values:
        if v is None or not _finite(v):
            continue
        x = float(v)
        d = 0
        while d < 7 and x != round(x, d):
            d += 1
        digits = max(digits, d)
    return digits


def panel_width_for(title: str) -> int:
    """The panel width (pixels) that shows ``title`` whole, and plots and images at a readable size."""
    return int(min(640, max(PANEL_WIDTH, _HEADER_PX + _TITLE_PX_PER_CHAR * len(title))))


class TextBinding:
    """A text property that may change at run time (a label with ``{expr}``) and its setter.

    ``shown`` is the text last sent; :meth:`Panel.refresh` calls ``show(text)`` only when
    the model's value makes a different one.
    """

    def __init__(self, prop: Any, where: str, show: Callable[[str], None], shown: str) -> None:
        self.prop = prop
        self.where = where
        self.show = show
        self.shown = shown


class ControlBinding:
    """One control and its viser handle.

    ``display(value)`` turns a model value into what the handle shows (or None to leave it);
    ``user_time`` is when the user last changed it (seconds on the panel's clock).
    """

    def __init__(self, control: Control, handle: Any, display: Callable[[Any], Any]) -> None:
        self.control = control
        self.handle = handle
        self.display = display
        self.getter = Dynamic(control.get, control.bind)
        self.user_time = -math.inf
        self.lock = threading.Lock()
        #: what the model last held, as shown (pushed or applied); the handle is written only
        #: when the model's value moves away from it, never just because the browser's
        #: in-progress text differs (which raced with typing on a loaded machine)
        self.last: Any = _UNSET


def _key(label: Any) -> str:
    """How a label is looked up (tests, scripted input): its spec text, ``{expr}`` and all."""
    return label.source if isinstance(label, Dynamic) else ("" if label is None else str(label))


def _set_tab_label(group: Any, index: int, text: str) -> None:
    labels = list(group._tab_labels)
    labels[index] = text
    group._tab_labels = tuple(labels)


def _same_value(a: Any, b: Any) -> bool:
    try:
        return bool(a == b) and type(a) is type(b)
    except Exception:  # noqa: BLE001 - odd values: treat as changed
        return False


def _display_fn(control: Control, digits: int | None = None) -> Callable[[Any], Any]:
    """How a model value is shown by the control's handle (None: cannot show it).

    ``digits``: the decimals a number box shows (its viser ``precision``); a value that
    would read -0.0 there (-0.0 itself, or -1e-9 at one decimal) is shown as 0."""
    if isinstance(control, Dropdown):
        options = list(control.options)

        def show_option(v: Any) -> Any:
            for opt in options:
                try:
                    if type(opt) is type(v) and opt == v:
                        return option_label(opt)
                except Exception:
                    continue
            for opt in options:  # 2 == 2.0, numpy scalars
                try:
                    if not isinstance(opt, str) and not isinstance(v, str) and bool(opt == v):
                        return option_label(opt)
                except Exception:
                    continue
            return None

        return show_option
    if isinstance(control, Checkbox) or control.vtype == "bool":
        return lambda v: None if v is None else bool(v)
    if isinstance(control, Text) or control.vtype == "str":
        return lambda v: None if v is None else str(v)

    lo = getattr(control, "min", None)
    hi = getattr(control, "max", None)
    is_int = control.vtype == "int"

    def show_number(v: Any) -> Any:
        if isinstance(v, (bool, np.bool_)) or not _finite(v):
            return None
        x = float(v)
        if lo is not None:
            x = max(x, float(lo))
        if hi is not None:
            x = min(x, float(hi))
        if is_int:
            return int(round(x))
        if digits is not None and abs(x) < 0.5 * 10.0**-digits:
            x = 0.0  # round-off about zero (a joint at -1e-15 deg) reads 0.0, not -0.0
        return x + 0.0  # -0.0 -> 0.0

    return show_number


class Panel:
    """The GUI of one app: control bar, error box, about, and the view's elements.

    ``app``: the running app (see :mod:`ejsrl.view.viser_view`); ``gui``: ``server.gui``;
    ``notify(client or None, title, body, color)`` shows a notification (None: everyone);
    ``clock()``: seconds on a monotonic clock, for the hold after a user's change and the
    plots' and images' rates (the real one by default; tests pass their own).
    """

    def __init__(self, app: Any, gui: Any, notify: Notify, *, clock: Callable[[], float] = time.monotonic) -> None:
        self.app = app
        self.gui = gui
        self.notify = notify
        self.clock = clock
        self.controls: list[ControlBinding] = []
        self.labels: list[tuple[Label, Any]] = []
        #: the labels of controls, buttons, folders, tabs, plots and images that hold {expr}
        self.texts: list[TextBinding] = []
        self._label_shown: dict[int, str] = {}
        self.plots: list[PlotBinding] = []
        self.images: list[ImageBinding] = []
        #: the tables and consoles (``ejsrl.view._table.TableBinding``, ``ejsrl.view._console.ConsoleBinding``)
        self.text_views: list[Any] = []
        #: the 2D drawing panels (ejsrl.view._drawing.DrawingBinding)
        self.drawings: list[Any] = []
        self.buttons: dict[str, Any] = {}
        self.handles_by_label: dict[str, Any] = {}
        self._error_rev_shown: int | None = None
        self._error_notes: list[Any] = []
        self._playing_shown: bool | None = None
        self._readout_shown: str | None = None
        self.play_button: Any = None
        self.step_button: Any = None
        self.reset_button: Any = None
        self.readout: Any = None
        #: the independent variable shown next to the control bar (the model's ``INDEPENDENT``)
        self._time_name: str | None = getattr(getattr(app, "model", None), "INDEPENDENT", None)
        self._build()

    # -- building ---------------------------------------------------------------------------
    def _build(self) -> None:
        app, gui = self.app, self.gui
        meta = getattr(app, "meta", None)
        title = getattr(meta, "title", "") or "ejsgen simulation"
        gui.set_panel_label(title)
        width = getattr(getattr(app, "sim", None), "panel_width", None) or panel_width_for(title)
        #: False for a lab without a 3D scene: its panel takes the window (:data:`NO_SCENE_WIDTH`)
        self.has_scene = has_scene(getattr(app, "view", None))
        if not self.has_scene:
            width = NO_SCENE_WIDTH
        # docked at the right edge: the panel never covers the 3D view, and it gets the
        # window's full height for plots and camera images
        gui.main_panel.dock_right()
        gui.main_panel.set_width(float(width))
        self.client_tweaks = gui.add_html(CLIENT_TWEAKS if self.has_scene else CLIENT_TWEAKS + NO_SCENE_TWEAKS)
        self.error_box = gui.add_html("", visible=False)
        if getattr(getattr(app, "sim", None), "controls", True):
            self._build_controls_bar()
        description = getattr(meta, "description", "") or ""
        author = getattr(meta, "author", "") or ""
        self.about: Any = None
        if description or author:
            # the lab's instructions, open from the start in their own panel at the left
            # edge, so that they push no control, plot or camera image out of sight
            text = description
            if author:
                text += f"\n\n*Author: {author}*"
            if not self.has_scene:  # in the panel, which has the window (a docked About would be squeezed)
                self.about = gui.add_folder("About")
                with self.about:
                    self.about_text = gui.add_markdown(text)
            else:
                self.about = gui.add_panel()
                with self.about.add_tab("About"):
                    self.about_text = gui.add_markdown(text)
                self.about.dock_left()
                self.about.set_width(ABOUT_WIDTH)
        if hasattr(getattr(app, "model", None), "_plant"):  # a remote laboratory (plant:): mode switch and e-stop first
            from ejsrl.plant._panel import PlantPanel

            self.drawings.append(PlantPanel(gui, app))
        self._build_elements(list(getattr(app, "view", []) or []))

    def _build_controls_bar(self) -> None:
        """Play/Pause, Step, Reset and the time readout; a model with nothing to step (no
        evolution, no programs) gets Reset alone, since Play would change nothing."""
        gui, app = self.gui, self.app
        evolves = getattr(getattr(app, "model", None), "_ejs_evolves", lambda: True)()
        if evolves:
            playing = bool(app.is_playing())
            self.play_button = gui.add_button("Pause" if playing else "Play", icon=None, color="orange" if playing else "green")
            self.step_button = gui.add_button("Step")
            self._playing_shown = playing

            @self.play_button.on_click
            def _(_e: Any) -> None:
                if app.is_playing():
                    app.pause()
                else:
                    app.play()
                self._show_playing()

            @self.step_button.on_click
            def _(_e: Any) -> None:
                app.step_once()

        self.reset_button = gui.add_button("Reset")
        self.readout = gui.add_markdown("") if evolves else None

        @self.reset_button.on_click
        def _(_e: Any) -> None:
            app.reset()

    def _build_elements(self, elements: list[Any]) -> None:
        gui = self.gui
        for el in elements:
            try:
                if isinstance(el, Folder):
                    folder = gui.add_folder(self._text(el.label, el.where), expand_by_default=el.expanded)
                    self._track(el.label, el.where, folder, "label")
                    with folder:
                        self._build_elements(el.children)
                elif isinstance(el, Tabs):
                    group = gui.add_tab_group()
                    for i, (label, children) in enumerate(el.tabs):
                        with group.add_tab(self._text(label, el.where)):
                            self._build_elements(children)
                        if is_dynamic(label):
                            self.texts.append(TextBinding(label, el.where, lambda t, g=group, i=i: _set_tab_label(g, i, t), self._text(label, el.where)))
                elif isinstance(el, Markdown):
                    gui.add_markdown(el.text)
                elif isinstance(el, Label):
                    handle = gui.add_markdown("" if is_dynamic(el.text) else keep_spaces(str(el.text)))
                    self.labels.append((el, handle))
                elif isinstance(el, Control):
                    self._build_control(el)
                elif isinstance(el, Button):
                    self._build_button(el)
                elif isinstance(el, Plot):
                    x_label = getattr(el.x, "source", "") or self._time_name or "x"
                    labels = [self._text(s.label, s.where or el.where) for s in el.series]
                    binding = PlotBinding(gui, el, x_label=x_label, title=self._text(el.title, el.where), labels=labels, clock=self.clock,
                                          height=el.height or (None if self.has_scene else NO_SCENE_PLOT_HEIGHT), key=f"plot-{len(self.plots)}")
                    self.plots.append(binding)
                    if is_dynamic(el.title):
                        self.texts.append(TextBinding(el.title, el.where, binding.set_title, binding.title))
                    for i, s in enumerate(el.series):
                        if is_dynamic(s.label):
                            self.texts.append(TextBinding(s.label, s.where or el.where, lambda t, b=binding, i=i: b.set_label(i, t), labels[i]))
                elif isinstance(el, Image):
                    binding = ImageBinding(gui, el, label=self._text(el.label, el.where), clock=self.clock,
                                           first=lambda el=el: self._image_now(el))
                    self.images.append(binding)
                    self._track(el.label, el.where, binding.handle, "label")
                elif isinstance(el, Drawing):
                    from ejsrl.view._drawing import DrawingBinding

                    self.drawings.append(DrawingBinding(gui, el, self.app, key=f"drawing-{len(self.drawings)}", clock=self.clock))
                elif isinstance(el, SceneKeys):
                    from ejsrl.view._drawing import SceneKeysBinding

                    self.drawings.append(SceneKeysBinding(gui, el, self.app, key=f"scene-keys-{len(self.drawings)}"))
                elif isinstance(el, Table):
                    from ejsrl.view._table import TableBinding

                    self.text_views.append(TableBinding(gui, el, self._locked_value))
                elif isinstance(el, Console):
                    from ejsrl.view._console import ConsoleBinding

                    self.text_views.append(ConsoleBinding(gui, el, self.app))
                elif isinstance(el, Scene):
                    pass  # mirrored from the world by the scene mirror
                else:
                    log.warning("ejsrl.view: no GUI for %r", type(el).__name__)
            except Exception as exc:  # a bad element must not take the whole panel down
                log.exception("ejsrl.view: could not build %s at %s", type(el).__name__, el.where)
                gui.add_markdown(f"*Could not show {type(el).__name__} ({el.where}): {exc}*")

    def _text(self, prop: Any, where: str) -> str:
        """The current text of a label property (constant, or ``Dynamic`` read now)."""
        if not is_dynamic(prop):
            return "" if prop is None else str(prop)
        with self.app.lock:
            value = self.app.safe_value(prop, where)
        return "" if value is None else str(value)

    def _locked_value(self, prop: Any, where: str) -> Any:
        """A property's value read now, the model lock held (while the panel is built)."""
        with self.app.lock:
            return self.app.safe_value(prop, where)

    def _image_now(self, el: Image) -> tuple[Any, Any]:
        """An image element's source and points read now (its first picture), the model lock held."""
        with self.app.lock:
            src = self.app.safe_value(el.source, el.where)
            pts = self.app.safe_value(el.points, el.where) if el.points is not None and src is not None else None
            got = self.app.guard(lambda: picture_of(src, pts, self._text(el.label, el.where)), el.where)
        return (None, None) if got is None else got

    def _track(self, prop: Any, where: str, handle: Any, attr: str) -> None:
        """Keep ``handle.<attr>`` showing ``prop`` if it changes at run time."""
        if is_dynamic(prop):
            self.texts.append(TextBinding(prop, where, lambda t: setattr(handle, attr, t), str(getattr(handle, attr))))

    def _initial(self, control: Control) -> Any:
        with self.app.lock:
            if self.app.error is None:
                value = self.app.safe_value(Dynamic(control.get, control.bind), control.where)
            else:  # the lab failed to start: show the value the variable has (its spec value), not the control's minimum
                try:
                    value = control.get(self.app.model)
                except Exception:  # noqa: BLE001 - it has none: the control's own default
                    value = None
        return _display_fn(control)(value)

    def _build_control(self, c: Control) -> None:
        gui = self.gui
        label = self._text(c.label, c.where) or c.bind
        shown = self._initial(c)
        hint = f"{c.bind}" if label != c.bind else None
        if isinstance(c, Slider):
            is_int = c.vtype == "int"
            lo, hi = float(c.min), float(c.max)
            step = c.step if c.step else (1 if is_int else (hi - lo) / 100 if hi > lo else 0.01)
            if is_int:
                lo_i, hi_i, step_i = int(math.ceil(lo)), int(math.floor(hi)), max(1, int(round(step)))
                init = lo_i if shown is None else int(min(max(shown, lo_i), hi_i))
                handle = gui.add_slider(label, min=lo_i, max=hi_i, step=step_i, initial_value=init, hint=hint)
            else:
                init = lo if shown is None else float(shown)
                handle = gui.add_slider(label, min=lo, max=hi, step=float(step), initial_value=init, hint=hint)
                # the box beside the slider (3 rem wide) shows the value to the step, as the
                # track's marks do: viser's precision also covers the initial value (pi/2: 7 digits)
                handle.precision = shown_digits(lo, hi, step)
        elif isinstance(c, Number) or (not isinstance(c, (Checkbox, Text, Dropdown)) and c.vtype in ("float", "int")):
            lo = getattr(c, "min", None)
            hi = getattr(c, "max", None)
            step = getattr(c, "step", None)
            if c.vtype == "int":
                init = 0 if shown is None else int(shown)
                if lo is not None and init < lo:
                    init = int(math.ceil(lo))
                if hi is not None and init > hi:
                    init = int(math.floor(hi))
                handle = gui.add_number(label, init, min=lo, max=hi, step=step or 1, hint=hint)
            else:
                init = 0.0 if shown is None else float(shown)
                if lo is not None and init < lo:
                    init = float(lo)
                if hi is not None and init > hi:
                    init = float(hi)
                handle = gui.add_number(label, init, min=lo, max=hi, step=step, hint=hint)
                if step:
                    handle.precision = shown_digits(lo, hi, step)
        elif isinstance(c, Checkbox) or c.vtype == "bool":
            handle = gui.add_checkbox(label, bool(shown) if shown is not None else False, hint=hint)
        elif isinstance(c, Dropdown):
            options = [option_label(o) for o in c.options] or ["(none)"]
            handle = gui.add_dropdown(label, options, initial_value=shown if shown in options else options[0], hint=hint)
        else:
            handle = gui.add_text(label, "" if shown is None else str(shown), hint=hint)
        precision = getattr(handle, "precision", None)
        binding = ControlBinding(c, handle, _display_fn(c, precision if isinstance(precision, int) else None))
        self.controls.append(binding)
        self.handles_by_label[_key(c.label) or c.bind] = handle
        self._track(c.label, c.where, handle, "label")
        handle.on_update(lambda event, b=binding: self._on_user_change(b, event))

    def _build_button(self, b: Button) -> None:
        handle = self.gui.add_button(self._text(b.label, b.where))
        self.buttons[_key(b.label)] = handle
        self._track(b.label, b.where, handle, "label")

        @handle.on_click
        def _(_e: Any) -> None:
            self.app.run_action(b)

    # -- values from the browser -----------------------------------------------------------------
    def _on_user_change(self, b: ControlBinding, event: Any) -> None:
        """A control changed; only changes made by a client are applied to the model."""
        if getattr(event, "client", None) is None:
            return  # our own refresh assigned the handle
        with b.lock:
            b.user_time = self.clock()
            raw = b.handle.value
            checked = validate_control(b.control, raw)
            if not checked.ok:
                self.notify(event.client, "Value refused", checked.message, "red")
                with self.app.lock:
                    current = b.display(self.app.safe_value(b.getter, b.control.where))
                b.user_time = -math.inf
                if current is not None:
                    b.handle.value = current
                    b.last = current
                return
            self.app.apply_control(b.control, checked.value)
            shown = b.display(checked.value)
            b.last = shown if shown is not None else _UNSET
            if shown is not None and shown != raw:
                b.handle.value = shown  # show the clamped / rounded value

    def set_from_client(self, b: ControlBinding, raw: Any, client: Any = object()) -> None:
        """Apply ``raw`` as if a browser had sent it (used by tests and scripted input)."""
        b.handle._impl.value = raw  # what viser stores before calling on_update

        class _Event:
            pass

        e = _Event()
        e.client = client  # type: ignore[attr-defined]
        self._on_user_change(b, e)

    # -- every frame --------------------------------------------------------------------------
    def refresh(self) -> None:
        """Push the model's current values (caller holds ``app.lock``)."""
        app = self.app
        self._show_playing()
        self._show_readout()
        now = self.clock()
        for label, handle in self.labels:
            if not is_dynamic(label.text):
                continue
            text = app.safe_value(label.text, label.where)
            if text is not None:
                content = keep_spaces(str(text))
                if self._label_shown.get(id(handle)) != content:
                    set_markdown(handle, content)
                    self._label_shown[id(handle)] = content
        for t in self.texts:
            value = app.safe_value(t.prop, t.where)
            if value is not None and str(value) != t.shown:
                t.shown = str(value)
                t.show(t.shown)
        for b in self.controls:
            if now - b.user_time < USER_HOLD_SECONDS:
                continue
            shown = b.display(app.safe_value(b.getter, b.control.where))
            if shown is not None and (b.last is _UNSET or not _same_value(shown, b.last)):
                b.handle.value = shown
                b.last = shown
        playing = bool(app.is_playing())
        for p in self.plots:
            p.update(app, playing=playing, now=now)  # one clock reading: the plots are sent in the same frames
        for d in self.drawings:
            d.refresh()
        for tv in self.text_views:
            tv.refresh(app.safe_value)
        for im in self.images:
            if not im.due():
                continue  # not rendered for nothing: the picture could not be sent yet
            src = app.safe_value(im.image.source, im.image.where)
            pts = app.safe_value(im.image.points, im.image.where) if im.image.points is not None else None
            got = app.guard(lambda: picture_of(src, pts, getattr(im.handle, "label", None) or ""), im.image.where) if src is not None else None
            if got is not None:
                im.update(*got)
        self._show_error()  # last: the expressions above may have just failed
        self._show_playing()

    def on_reset(self) -> None:
        """Forget plot data and cached images."""
        for p in self.plots:
            p.clear()
        for im in self.images:
            im.clear()
        for d in self.drawings:
            d.clear()
        for b in self.controls:
            b.user_time = -math.inf

    def _show_playing(self) -> None:
        if self.play_button is None:
            return
        playing = bool(self.app.is_playing())
        if playing != self._playing_shown:
            self.play_button.label = "Pause" if playing else "Play"
            self.play_button.color = "orange" if playing else "green"
            self._playing_shown = playing

    def _show_readout(self) -> None:
        if self.readout is None or not self._time_name:
            return
        value = getattr(getattr(self.app, "model", None), self._time_name, None)
        if value is None or not _finite(value):
            return
        text = f"**{self._time_name}** = {float(value):.6g}"
        speed = getattr(self.app, "speed", None) if self.app.is_playing() else None
        if speed is not None and speed < SLOW_SPEED:
            text += slow_text(speed, bool(getattr(getattr(self.app, "sim", None), "realtime", False)))
        else:
            shown = getattr(self.app, "shown_fps", None) if self.app.is_playing() else None
            asked = getattr(getattr(self.app, "sim", None), "fps", None)
            limit = SLOW_SHOWN_FPS if not asked else min(SLOW_SHOWN_FPS, SLOW_SPEED * float(asked))
            if shown is not None and shown < limit:
                text += f" · *showing {shown:.0f} frames/s ({BUSY})*"
        if text != self._readout_shown:
            set_markdown(self.readout, text)
            self._readout_shown = text

    def _show_error(self) -> None:
        rev = getattr(self.app, "error_rev", 0)
        if rev == self._error_rev_shown:
            return
        self._error_rev_shown = rev
        err = getattr(self.app, "error", None)
        for note in self._error_notes:
            try:
                note.remove()
            except Exception:
                pass
        self._error_notes = []
        if err is None:
            self.error_box.visible = False
            return
        import html

        where = getattr(err, "where", "") or ""
        message = str(getattr(err, "message", err))
        head = f"⚠ Error at {where}" if where else "⚠ Error"
        self.error_box.content = (
            '<div style="background:#fde8e8;border:1px solid #e03131;color:#c92a2a;'
            'border-radius:6px;padding:8px 10px;font-size:0.9em;white-space:pre-wrap;word-break:break-word">'
            f"<b>{html.escape(head)}</b><br>{html.escape(message)}"
            "<br><i>The simulation is paused; press Reset to start again.</i></div>"
        )
        self.error_box.visible = True
        self._error_notes = self.notify(None, head, message, "red")
