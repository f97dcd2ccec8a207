"""Robot programs: code that runs alongside the simulation in simulated time.

A program is compiled into a generator method of the model; each motion command is a
``yield from program.move_j(...)``, so the command takes simulated time and the program
goes on when it finishes, while other statements take none (as in the EjsRL paper's
pick-and-place experiment). After every simulation step the runner resumes each running
program once: a command then moves the program's joint variable along its planned
trajectory to the current time.

Commands: ``move_j(target, time=None, speed=None, mode="sync")`` (a joint vector, or a
4x4 pose solved by inverse kinematics from the current joints; synchronous or
asynchronous joint motion), ``move_l(pose, time=None, speed=None)`` (a straight line in
Cartesian space), ``wait(seconds)``, ``wait_until(condition)``, ``open_gripper()`` and
``close_gripper()`` (closing grasps the graspable object within reach; opening releases
it).
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from ejsrl.sim.names import prelude

__all__ = ["ProgramDef", "Program", "Programs", "ProgramError"]

#: default joint speed (rad/s or m/s for prismatic joints) when a move gives neither time nor speed
DEFAULT_JOINT_SPEED = 1.0
#: default tool speed (m/s) of move_l
DEFAULT_LINEAR_SPEED = 0.25
#: how long opening or closing the gripper takes (s)
GRIPPER_TIME = 0.3
#: how far (m) from the tool point a graspable object may be for close_gripper() to grasp it
GRASP_REACH = 0.08

Steps = Generator[None, None, None]


class ProgramError(RuntimeError):
    """A motion command could not be carried out (e.g. no inverse-kinematics solution)."""


@dataclass
class ProgramDef:
    """A program as the spec declares it: the variables it uses and its compiled body."""

    robot: str
    q: str
    body: Callable[[Any, Program], Any]
    gripper: str | None = None
    autostart: bool = False
    where: str = ""


class Program:
    """One program's run: its generator, state (idle, running, done, stopped, error) and commands."""

    def __init__(self, name: str, model: Any, spec: ProgramDef) -> None:
        self.name = name
        self.model = model
        self.spec = spec
        self.state = "idle"
        self.message = ""
        self.gen: Iterator[Any] | None = None
        self.grasped: str | None = None

    # -- what the runner does -------------------------------------------------------------
    def start(self) -> None:
        result = self.spec.body(self.model, self)
        self.gen = result if isinstance(result, Iterator) else iter(())
        self.state = "running"
        self.message = ""
        self.resume()

    def stop(self) -> None:
        if self.gen is not None and hasattr(self.gen, "close"):
            self.gen.close()
        self.gen = None
        if self.state == "running":
            self.state = "stopped"

    def resume(self) -> None:
        """Run until the next command needs more simulated time (or the program ends)."""
        if self.state != "running" or self.gen is None:
            return
        try:
            next(self.gen)
        except StopIteration:
            self.state = "done"
            self.gen = None
        except Exception as exc:  # noqa: BLE001 - user code: stop the program, not the app
            from ejsrl.sim.model import describe_error

            err = describe_error(exc, type(self.model))
            self.state = "error"
            self.message = f"{err.where}: {err.message}" if err.where else err.message
            self.gen = None
            self.model.alert(f"program '{self.name}' stopped: {self.message}")

    def line(self) -> int | None:
        """The spec line the program is at (while it runs)."""
        frame = getattr(self.gen, "gi_frame", None)
        if frame is None:
            return None
        table = getattr(type(self.model), "SPEC_LINES", {})
        hit = table.get(frame.f_lineno)
        return hit[0] if hit else None

    def status(self) -> str:
        """One line for the UI: state and current spec line."""
        if self.state == "running":
            line = self.line()
            return f"program '{self.name}': running" + (f", line {line}" if line else "")
        if self.state == "error":
            return f"program '{self.name}': stopped on an error at {self.message}"
        return f"program '{self.name}': {self.state}"

    # -- helpers ------------------------------------------------------------------------------
    def _now(self) -> float:
        t = self.model._ejs_time()
        if t is None:
            raise ProgramError("robot programs need an independent variable (time)")
        return t

    def _robot(self) -> Any:
        return getattr(self.model, self.spec.robot)

    def _q(self) -> np.ndarray:
        return np.array(getattr(self.model, self.spec.q), dtype=float).reshape(-1)

    def _set_q(self, q: np.ndarray) -> None:
        current = getattr(self.model, self.spec.q)
        if isinstance(current, np.ndarray) and current.shape == q.shape:
            current[...] = q
        else:
            setattr(self.model, self.spec.q, np.array(q, dtype=float))

    def _joint_target(self, target: Any) -> np.ndarray:
        arr = np.asarray(target, dtype=float)
        if arr.shape == (4, 4):
            sol = self._robot().ikine(arr, q0=self._q())
            if not sol.success:
                raise ProgramError(f"move_j: no inverse-kinematics solution for the target pose ({getattr(sol, 'reason', '')})")
            return np.asarray(sol.q, dtype=float)
        q = self._q()
        if arr.shape != q.shape:
            raise ProgramError(f"move_j: the target has {arr.size} values but '{self.spec.q}' has {q.size}")
        return arr

    def _follow(self, sample: Callable[[float], np.ndarray], duration: float) -> Steps:
        t0 = self._now()
        while True:
            elapsed = self._now() - t0
            if elapsed >= duration - 1e-12:
                self._set_q(sample(duration))
                return
            self._set_q(sample(elapsed))
            yield

    # -- the commands ----------------------------------------------------------------------------
    @prelude("command")
    def move_j(self, target: Any, time: float | None = None, speed: float | None = None, mode: str = "sync") -> Steps:
        """Move the joints to ``target`` (joint vector or 4x4 pose) in ``time`` s or at ``speed``."""
        from ejsrl.robotics import trajectory

        if mode not in ("sync", "async"):
            raise ProgramError(f"move_j: mode is 'sync' or 'async', not {mode!r}")
        q0 = self._q()
        q1 = self._joint_target(target)
        dq = np.abs(q1 - q0)
        if float(dq.max(initial=0.0)) < 1e-12:
            return
        if time is not None and time <= 0:
            raise ProgramError("move_j: time must be positive")
        if speed is not None and speed <= 0:
            raise ProgramError("move_j: speed must be positive")
        if mode == "sync" and time is not None:
            # every joint starts and ends together, on a smooth quintic profile
            traj = trajectory.quintic(q0, q1, float(time), num=2)
        else:
            # trapezoidal velocity at the given peak joint speed: synchronous (the slowest joint
            # sets the time and the others are slowed to end with it) or asynchronous (each
            # joint at full speed, ending on its own)
            v = float(speed) if speed is not None else DEFAULT_JOINT_SPEED
            if mode == "async" and time is not None:
                v = 2.0 * float(dq.max()) / float(time)
            vmax = np.full(q0.shape, v)
            amax = 4.0 * vmax
            plan = trajectory.synchronous if mode == "sync" else trajectory.asynchronous
            traj = plan(q0, q1, vmax=vmax, amax=amax, num=2)
        yield from self._follow(lambda t: traj.sample(t)[0], float(traj.T))

    @prelude("command")
    def move_l(self, pose: Any, time: float | None = None, speed: float | None = None) -> Steps:
        """Move the tool along a straight line to ``pose`` (4x4), orientation by SLERP."""
        from ejsrl.robotics import trajectory

        robot = self._robot()
        T1 = np.asarray(pose, dtype=float)
        if T1.shape != (4, 4):
            raise ProgramError("move_l: the target must be a 4x4 pose")
        T0 = robot.fkine(self._q())
        dist = float(np.linalg.norm(T1[:3, 3] - T0[:3, 3]))
        v = float(speed) if speed is not None else DEFAULT_LINEAR_SPEED
        duration = float(time) if time is not None else max(1.5 * dist / v, 0.2)
        path = trajectory.ctraj(T0, T1, duration, num=2)

        def sample(t: float) -> np.ndarray:
            Tt = path.sample(t)[0]
            sol = robot.ikine(Tt, q0=self._q())
            if not sol.success:
                raise ProgramError(f"move_l: the line leaves the arm's reach at t = {t:.3f} s")
            return np.asarray(sol.q, dtype=float)

        yield from self._follow(sample, duration)

    @prelude("command")
    def wait(self, seconds: float) -> Steps:
        """Let ``seconds`` of simulated time pass."""
        t0 = self._now()
        while self._now() - t0 < float(seconds) - 1e-12:
            yield

    @prelude("command")
    def wait_until(self, condition: Callable[[], Any]) -> Steps:
        """Wait until ``condition()`` is true (checked once a step)."""
        while not condition():
            yield

    def _gripper_to(self, value: float) -> Steps:
        name = self.spec.gripper
        if name is None:
            yield from self.wait(GRIPPER_TIME)
            return
        start = float(getattr(self.model, name))
        t0 = self._now()
        while True:
            s = min((self._now() - t0) / GRIPPER_TIME, 1.0)
            setattr(self.model, name, start + (value - start) * s)
            if s >= 1.0:
                return
            yield

    @prelude("command")
    def open_gripper(self) -> Steps:
        """Open the gripper, releasing what it holds."""
        if self.grasped is not None:
            self.model.release(self.grasped)
            self.grasped = None
        yield from self._gripper_to(1.0)

    @prelude("command")
    def close_gripper(self) -> Steps:
        """Close the gripper, grasping the graspable object within reach of the tool (if any)."""
        yield from self._gripper_to(0.0)
        robot = self._robot()
        tool = robot.fkine(self._q())[:3, 3]
        found = self.model._ejs_world.world_functions().graspable_near(robot, tool, GRASP_REACH)
        if found is not None:  # else nothing within reach, or the arm is not drawn
            obj, element = found
            self.model.attach(obj, element)
            self.grasped = obj


class Programs:
    """The programs of a model: started and stopped by name, resumed after every step."""

    def __init__(self, model: Any, defs: dict[str, ProgramDef]) -> None:
        self.model = model
        self.programs = {name: Program(name, model, d) for name, d in defs.items()}

    def _get(self, name: str) -> Program:
        try:
            return self.programs[name]
        except KeyError:
            import difflib

            close = difflib.get_close_matches(str(name), list(self.programs), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise KeyError(f"no program named '{name}'{hint}") from None

    def start(self, name: str) -> None:
        """Start (or restart) the program ``name``."""
        program = self._get(name)
        program.stop()
        program.start()

    def stop(self, name: str) -> None:
        """Stop the program ``name``."""
        self._get(name).stop()

    def reset(self) -> None:
        """Stop every program, then start those marked ``autostart``."""
        self.stop_all()
        self.autostart()

    def stop_all(self) -> None:
        """Stop every program and forget what it held: each is ``idle`` again (a reset, before ``init``)."""
        for p in self.programs.values():
            p.stop()
            p.state = "idle"
            p.grasped = None

    def autostart(self) -> None:
        """Start the programs marked ``autostart`` that are still ``idle`` (``init`` may have
        started one already: it is not started a second time)."""
        for p in self.programs.values():
            if p.spec.autostart and p.state == "idle":
                p.start()

    def advance(self) -> None:
        """Resume every running program once (after a simulation step)."""
        for p in self.programs.values():
            if p.state == "running":
                p.resume()

    def status(self, name: str) -> str:
        return self._get(name).status()
