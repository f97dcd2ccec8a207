"""Model-exchange events at the end of a step, with a scripted stand-in for an FMU instance
(the lab's FMU has none): the FMU asking for event mode after a step, a time event it
announced, and a sign change of an event indicator each run the event iteration, take the
states the FMU changed and restart the page's solver; nothing happens otherwise."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from ejsrl.fmi.coupling import FmuDef, FmuRun


class Script:
    """Records the calls an FmuRun makes; answers as told."""

    def __init__(self, *, enter: bool = False, z: tuple[float, ...] = (), next_time: float | None = None) -> None:
        self.calls: list[str] = []
        self.enter = enter
        self.z = np.array(z, dtype=float)
        self.next_time = next_time
        self.nx = 1
        self.states_after_event = np.array([42.0])

    def set_time(self, t: float) -> None:
        self.calls.append("set_time")

    def set_states(self, x: np.ndarray) -> None:
        self.calls.append("set_states")

    def completed_step(self) -> bool:
        self.calls.append("completed_step")
        return self.enter

    def event_indicators(self) -> np.ndarray:
        return self.z

    def enter_event_mode(self) -> None:
        self.calls.append("enter_event_mode")

    def event_update(self) -> tuple[bool, float | None]:
        self.calls.append("event_update")
        return True, self.next_time

    def enter_continuous_time_mode(self) -> None:
        self.calls.append("enter_continuous_time_mode")

    def get_states(self) -> np.ndarray:
        return self.states_after_event


class Page:
    restarts = 0

    def restart(self) -> None:
        self.restarts += 1


def run_with(script: Script, z_before: tuple[float, ...] = (), next_event: float | None = None) -> tuple[FmuRun, Page]:
    run = FmuRun(model=None, spec=FmuDef("f", "f.fmu", "model_exchange", ode=0, where="lab.ejs.yaml:3:3"), base_dir=Path("."))
    run.inst = script  # type: ignore[assignment]
    run.x = np.array([1.0])
    run.z = np.array(z_before, dtype=float)
    run.next_event = next_event
    run.page = Page()
    return run, run.page


@pytest.mark.parametrize(
    "script, z_before, next_event",
    [
        (Script(enter=True), (), None),  # the FMU asks for event mode
        (Script(), (), 0.05),  # a time event it announced is reached
        (Script(z=(-1.0,)), (1.0,), None),  # an event indicator changed sign
    ],
    ids=["step event", "time event", "state event"],
)
def test_an_event_runs_the_event_iteration_and_restarts_the_solver(script, z_before, next_event):
    run, page = run_with(script, z_before, next_event)
    run._me_after_step(0.1)
    i = script.calls.index("completed_step")  # after the FMU took the step's final state
    assert script.calls[:i] == ["set_time", "set_states"]
    assert script.calls[i + 1 :] == ["enter_event_mode", "event_update", "enter_continuous_time_mode"]
    assert run.x.tolist() == [42.0]  # the states the FMU changed in the event
    assert page.restarts == 1
    assert run.t == 0.1


def test_no_event_no_iteration():
    script = Script(z=(1.0,))
    run, page = run_with(script, (0.5,), 0.5)
    run._me_after_step(0.1)
    assert "enter_event_mode" not in script.calls and "completed_step" in script.calls
    assert run.x.tolist() == [1.0] and page.restarts == 0
