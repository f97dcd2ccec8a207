"""The spec's ``plant:`` section: a remote laboratory's link to a real plant (issue #26).

The models (validated by pydantic, documented in specs/language.md from their docstrings) and
``compile_plant``, which checks the links against the model's variables at FILE:LINE:COL and
writes the model's ``_plant()`` method: the plant declaration the app's plant panel
(:mod:`ejsrl.app._plant_link`) connects with. Credentials are never part of a spec: keys such as
``password`` are refused with a hint to the environment or a credentials file.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal, Union

from pydantic import Field, model_validator

from ejsgen.errors import SpecError
from ejsgen.plan import Line

if TYPE_CHECKING:
    from ejsgen.compiler import Compiler

__all__ = ["Plant", "PlantCommand", "PlantMeasurement", "PlantVideo", "compile_plant"]

from ejsgen.spec import Strict  # noqa: E402  (spec.py imports this module after defining Strict)

_SECRET_KEYS = ("password", "username", "user", "token", "secret", "credentials", "tls_key", "key", "cert")
_SECRET_HINT = ("credentials never go in a spec (it is copied into app.py): set EJSRL_PLANT_USERNAME and "
                "EJSRL_PLANT_PASSWORD where the app runs, or name a file with EJSRL_PLANT_CREDENTIALS=FILE")

#: what a measurement may read: the plant's state, or the link's own view of it
MEASURED = Literal["joints", "speeds", "gripper", "status", "event", "latency", "video_age", "queue_position", "holds_lease", "connected"]
_TIMES = ("latency", "video_age")
#: units a joint or latency value is converted to and from (SI inside the plant)
UNITS = Literal["rad", "deg", "s", "ms"]
_SCALE = {"rad": 1.0, "deg": 3.141592653589793 / 180.0, "s": 1.0, "ms": 1e-3}


class PlantCommand(Strict):
    """A model variable sent to the plant in Real plant mode."""

    to: Literal["joints", "gripper"]
    """What it drives: ``joints`` (the arm's 5 set points, an array variable) or ``gripper`` (0 closed .. 1 open)."""
    unit: Literal["rad", "deg"] = "rad"
    """The variable's unit (joints); the plant takes radians."""
    min: Union[float, list[float], None] = None
    """Lower limit(s) in the variable's unit, checked by the app before sending (the plant checks its own limits again)."""
    max: Union[float, list[float], None] = None
    """Upper limit(s) in the variable's unit, checked before sending."""
    max_speed: float | None = Field(default=None, gt=0)
    """Fastest change of any joint between two commands, in the variable's unit per second."""


class PlantMeasurement(Strict):
    """A model variable that receives a value measured by the plant (in Real plant mode, and while watching)."""

    source: MEASURED = Field(alias="from")
    """What it reads: ``joints`` (5 angles), ``speeds``, ``gripper``, ``status`` (text), ``event`` (text: what the plant last did), ``latency`` (command round trip), ``video_age`` (the newest camera frame's age), ``queue_position`` (0: not waiting), ``holds_lease`` (1 or 0), ``connected`` (1 or 0)."""
    unit: UNITS = "rad"
    """The variable's unit: rad or deg for joints and speeds (per s), s or ms for latency and video_age."""


class PlantVideo(Strict):
    """The plant's camera, shown in Real plant mode with the age of the frame on screen."""

    stale: float = Field(default=0.5, gt=0, le=60)
    """Seconds: a frame older than this is flagged STALE (the camera or the plant stopped, the network is slow)."""
    rate: float = Field(default=15.0, gt=0, le=60)
    """At most this many frames a second go to each page (the newest one; the others are dropped)."""


class Plant(Strict):
    """The real plant a remote laboratory drives (the paper's RobUALab); run `python -m ejsrl.plant` for the reference plant."""

    transport: Literal["mqtt", "opcua"] = "mqtt"
    """How the app reaches the plant: ``mqtt`` through a broker (paho-mqtt), or ``opcua`` straight to the plant's OPC UA server (asyncua; the port is then the server's, e.g. 4840)."""
    host: str = "127.0.0.1"
    """The broker's host, or the OPC UA server's (the environment's EJSRL_PLANT_HOST wins, so a lab moves without editing its spec)."""
    port: int = Field(default=1883, ge=1, le=65535)
    """The broker's port, or the OPC UA server's (EJSRL_PLANT_PORT wins)."""
    topic: str = Field(default="ejsrl/plant", pattern=r"^[A-Za-z0-9_\-/]+$")
    """The plant's topic prefix (letters, digits, _, - and /)."""
    heartbeat: float = Field(default=0.1, gt=0, le=5)
    """Seconds between the app's heartbeats; the plant's watchdog stops it when they stop."""
    rate: float = Field(default=20.0, gt=0, le=200)
    """At most this many commands per second."""
    commands: dict[str, PlantCommand] = Field(default_factory=dict)
    """Model variable: what it drives on the plant."""
    measurements: dict[str, PlantMeasurement] = Field(default_factory=dict)
    """Model variable: what it receives from the plant."""
    video: PlantVideo | None = None
    """The plant's camera stream, shown in Real plant mode with its age (``video: {}`` for the defaults)."""

    @model_validator(mode="before")
    @classmethod
    def _no_credentials(cls, data: Any) -> Any:
        if isinstance(data, dict):
            for key in data:
                if isinstance(key, str) and key.lower() in _SECRET_KEYS:
                    raise ValueError(f"'{key}' cannot be in a spec: {_SECRET_HINT}")
        return data


def _limits(c: Compiler, cmd: PlantCommand, path: tuple[Any, ...], n: int) -> tuple[list[float], list[float]] | None:
    out = []
    wide = (0.0, 1.0) if cmd.to == "gripper" else (-1e9, 1e9)
    for side, default in (("min", wide[0]), ("max", wide[1])):
        v = getattr(cmd, side)
        if v is None:
            out.append([default] * n)
        elif isinstance(v, list):
            if len(v) != n:
                c.errors.append(SpecError(c.loc(path + (side,)), f"{side} gives {len(v)} limits for {n} joints", f"give one number for all joints or a list of {n}"))
                return None
            out.append([float(x) for x in v])
        else:
            out.append([float(v)] * n)
    if any(lo > hi for lo, hi in zip(*out)):
        c.errors.append(SpecError(c.loc(path + ("min",)), "a lower limit is above its upper limit"))
        return None
    return out[0], out[1]


def compile_plant(c: Compiler) -> None:
    """Check the plant's links against the model's variables; add ``_plant()`` to the model."""
    from ejsgen._suggest import did_you_mean

    plant = c.spec.plant
    if plant is None:
        return
    names = list(c.var_decls)
    cmds, meas = [], []
    for kind, links in (("commands", plant.commands), ("measurements", plant.measurements)):
        for var, link in links.items():
            path: tuple[Any, ...] = ("plant", kind, var)
            if var not in c.var_decls:
                c.errors.append(SpecError(c.doc.key_loc(path), f"'{var}' is not a model variable", did_you_mean(var, names) or "declare it under model: variables:"))
                continue
            if kind == "commands":
                n = 5 if link.to == "joints" else 1
                lim = _limits(c, link, path, n)
                if lim is None:
                    continue
                scale = _SCALE[link.unit] if link.to == "joints" else 1.0
                speed = None if link.max_speed is None else link.max_speed * scale
                cmds.append(f"PlantCommand({var!r}, {link.to!r}, scale={scale!r}, q_min={[x * scale for x in lim[0]]!r}, "
                            f"q_max={[x * scale for x in lim[1]]!r}, max_speed={speed!r}),")
            else:
                if (link.unit in ("s", "ms")) != (link.source in _TIMES):
                    c.errors.append(SpecError(c.loc(path + ("unit",)), f"'{link.unit}' is not a unit of {link.source}",
                                              "latency and video_age are in s or ms (give unit: ms); joints and speeds in rad or deg"))
                    continue
                meas.append(f"PlantMeasurement({var!r}, {link.source!r}, scale={_SCALE[link.unit]!r}),")
    if sum(1 for l in plant.commands.values() if l.to == "joints") > 1:
        c.errors.append(SpecError(c.loc(("plant", "commands")), "more than one variable drives the joints", "keep one command with to: joints"))
    lines = [Line("from ejsrl.app._plant_link import PlantCommand, PlantDef, PlantMeasurement"), Line(""),
             Line(f"return PlantDef({plant.host!r}, {plant.port!r}, topic={plant.topic!r}, heartbeat={plant.heartbeat!r}, rate={plant.rate!r},"),
             *([Line(f"    transport={plant.transport!r},")] if plant.transport != "mqtt" else []),
             *([Line(f"    video_stale={plant.video.stale!r}, video_rate={plant.video.rate!r},")] if plant.video else []),
             Line("    commands=["), *[Line("        " + s) for s in cmds], Line("    ],"),
             Line("    measurements=["), *[Line("        " + s) for s in meas], Line("    ],"), Line(")")]
    c.add_method("_plant", "self", "The real plant this lab drives (plant:); the plant panel connects to it, never the browser.", lines)
