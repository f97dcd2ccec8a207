"""A small hand-written lab (what the generator would emit) for the view's tests."""

from __future__ import annotations

import math

import numpy as np

from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.sim.model import CodePage, ModelBase
from ejsrl.view.elements import (
    Button,
    Checkbox,
    Dropdown,
    Dynamic,
    Folder,
    Image,
    Label,
    Markdown,
    Node3D,
    Number,
    Plot,
    Scene,
    Series,
    Slider,
    Tabs,
    Text,
)

SPEC = "lab.ejs.yaml"


class LabModel(ModelBase):
    SPEC = SPEC
    VARIABLES = {"t": "float", "dt": "float", "L": "float", "n": "int", "on": "bool", "name": "str",
                 "mode": "str", "x": "float", "k": "float", "size": "float", "q": "array"}
    INDEPENDENT = "t"

    def _declare(self) -> None:
        self.t = 0.0
        self.dt = 0.1
        self.L = 1.0
        self.n = 3
        self.on = True
        self.name = "lab"
        self.mode = "fast"
        self.x = 0.0
        self.k = 1.0
        self.size = 0.2
        self.q = np.array([0.0, 0.5, 1.0])

    def _evolution(self) -> list:
        return [CodePage("move", self._move)]

    def _move(self) -> None:
        self.t += self.dt

    def _fixed_relations(self) -> None:
        self.x = self.L * math.sin(self.t)

    def ratio(self) -> float:
        return 1.0 / (self.k - 1.0)  # ZeroDivisionError when k == 1 and a view asks for it


def _bind(name: str):
    return (lambda m: getattr(m, name)), (lambda m, v: setattr(m, name, v))


def make_view(*, failing_label: bool = False) -> list:
    gL, sL = _bind("L")
    gn, sn = _bind("n")
    gon, son = _bind("on")
    gname, sname = _bind("name")
    gmode, smode = _bind("mode")
    view = [
        Folder("Parameters", [
            Slider("L", gL, sL, label="Length", min=0.1, max=2.0, step=0.1, where=f"{SPEC}:30:7"),
            Number("n", gn, sn, label="Count", vtype="int", min=0, max=10, where=f"{SPEC}:31:7"),
            Checkbox("on", gon, son, label="Enabled", vtype="bool"),
            Text("name", gname, sname, label="Name", vtype="str"),
            Dropdown("mode", gmode, smode, label="Mode", vtype="str", options=["slow", "fast"]),
            Slider("q[1]", lambda m: m.q[1], lambda m, v: m.q.__setitem__(1, v), label="q1", min=-1.0, max=1.0, step=0.01),
        ]),
        Tabs([
            ("Readings", [Label(Dynamic(lambda m: f"x = {m.x:.3f}", "f'x = {x:.3f}'"), where=f"{SPEC}:40:7")]),
            ("Notes", [Markdown("Some *notes*.")]),
        ]),
        Button("Double L", lambda m: setattr(m, "L", min(2.0, 2 * m.L)), where=f"{SPEC}:45:7"),
        Plot("x(t)", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.x, "x"), "x", "red"),
                                                     Series(Dynamic(lambda m: m.L, "L"), "L", None)],
             window=2.0, max_points=500),
        Image(Dynamic(lambda m: np.full((24, 32), int(m.n) * 20, np.uint8), "img"), "camera",
              points=Dynamic(lambda m: np.array([[5.0, 6.0]]), "pts")),
        Scene([
            Node3D("group", "arm", position=Dynamic(lambda m: (m.x, 0.0, 0.0), "[x,0,0]"), children=[
                Node3D("box", "block", props={"size": Dynamic(lambda m: (m.size, m.size, m.size), "[size]*3")},
                       position=(0.0, 0.0, 0.5), color=Dynamic(lambda m: "red" if m.on else "blue", "c")),
            ]),
            Node3D("sphere", "ball", props={"radius": 0.1}, position=(1.0, 0.0, 0.0)),
            Node3D("frame", "origin", props={"size": 0.3}),
            Node3D("cylinder", "post", props={"radius": 0.05, "height": 0.5}, position=(-1.0, 0.0, 0.25)),
            Node3D("trail", "path", props={"point": Dynamic(lambda m: (m.x, 0.0, 1.0), "p")}),
            Node3D("gizmo", "handle", props={"scale": 0.3}, transform=Dynamic(lambda m: np.eye(4), "T"),
                   set=lambda m, T: setattr(m, "k", float(T[0, 3]) + 2.0)),
        ]),
    ]
    if failing_label:
        view.insert(0, Label(Dynamic(lambda m: f"ratio = {m.ratio():.2f}", "ratio()"), where=f"{SPEC}:50:9"))
    return view


def make_app(**kw) -> App:
    failing = kw.pop("failing_label", False)
    clock = kw.pop("clock", None)
    extra = {} if clock is None else {"clock": clock}
    return App(LabModel, make_view(failing_label=failing), **extra,
               sim=SimConfig(fps=30.0, **kw),
               meta=AppMeta(title="Test lab", description="A **test** lab.", author="Tester", spec=SPEC))
