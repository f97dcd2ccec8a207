"""A small lab for the browser tests: a pendulum bob on a rod, a slider, a plot, a button."""

from __future__ import annotations

import math

from ejsrl.app import App, AppMeta, SimConfig
from ejsrl.sim.model import CodePage, ModelBase
from ejsrl.view.elements import Button, Dynamic, Folder, Label, Node3D, Plot, Scene, Series, Slider

SPEC = "pendulum.ejs.yaml"


class Pendulum(ModelBase):
    SPEC = SPEC
    VARIABLES = {"t": "float", "dt": "float", "L": "float", "theta": "float", "omega": "float", "x": "float", "z": "float"}
    INDEPENDENT = "t"

    def _declare(self) -> None:
        self.t = 0.0
        self.dt = 0.02
        self.L = 1.0
        self.theta = 0.6
        self.omega = 0.0
        self.x = 0.0
        self.z = 0.0

    def _evolution(self) -> list:
        return [CodePage("swing", self._swing)]

    def _swing(self) -> None:
        self.omega -= 9.81 / self.L * math.sin(self.theta) * self.dt
        self.theta += self.omega * self.dt
        self.t += self.dt

    def _fixed_relations(self) -> None:
        self.x = self.L * math.sin(self.theta)
        self.z = 1.5 - self.L * math.cos(self.theta)


def _break(m: Pendulum) -> None:
    m.L = 1.0 / (m.L - m.L)  # a user-code error, raised on purpose


VIEW = [
    Folder("Pendulum", [
        Slider("L", lambda m: m.L, lambda m, v: setattr(m, "L", v), label="Length", min=0.2, max=2.0, step=0.1,
               where=f"{SPEC}:20:7"),
        Label(Dynamic(lambda m: f"angle = {m.theta:.3f} rad", "f'angle = {theta:.3f} rad'")),
        Button("Break it", _break, where=f"{SPEC}:27:7"),
    ]),
    Plot("angle", Dynamic(lambda m: m.t, "t"), [Series(Dynamic(lambda m: m.theta, "theta"), "theta", "blue")], window=10.0),
    Scene([
        Node3D("grid", "floor", props={"size": 4.0, "cell": 0.25}),
        Node3D("line", "rod", props={"points": Dynamic(lambda m: [[0, 0, 1.5], [m.x, 0, m.z]], "rod")}, color="gray"),
        Node3D("sphere", "bob", props={"radius": 0.08}, position=Dynamic(lambda m: (m.x, 0.0, m.z), "[x, 0, z]"),
               color="orange"),
    ]),
]


def make_app() -> App:
    return App(Pendulum, VIEW, sim=SimConfig(fps=30.0),
               meta=AppMeta(title="Pendulum", description="A simple pendulum.", author="Tests", spec=SPEC))
