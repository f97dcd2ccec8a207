"""``ejsgen plant``: run the reference plant, or check a lab's ``plant:`` section against a live plant.

* ``ejsgen plant serve --mqtt HOST:PORT [--opcua HOST:PORT] ...`` runs the reference plant
  (:mod:`ejsrl.plant`, every option of ``python -m ejsrl.plant``) until interrupted;
* ``ejsgen plant check SPEC`` validates SPEC (errors at FILE:LINE:COL), connects to the plant its
  ``plant:`` section names (``EJSRL_PLANT_HOST``/``EJSRL_PLANT_PORT`` and the credentials from
  the environment or ``--credentials FILE``, as the app would) and says what a teacher needs to
  know before the class: the plant answers, its state comes at its rate, it measures as many
  joints as the lab commands, its clock's offset, and, for a lab with ``video:``, the camera's
  frames per second and their age. It never takes the lease, so it can run during a class.
  Exit status 0 when every check passed, 1 when one failed (each failure says why).
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

from ejsgen.errors import EjsError, SpecError

__all__ = ["add_parser", "cmd_plant"]


_DESCRIPTION = """\
ejsgen plant serve --mqtt HOST:PORT [--opcua HOST:PORT] [...]
    run the reference plant (a 5-axis arm with its lease, watchdog, e-stop and camera);
    `ejsgen plant serve --help` lists its options
ejsgen plant check SPEC
    validate SPEC, connect to the plant its plant: section names, as the app would
    (EJSRL_PLANT_HOST/PORT and the credentials from the environment or --credentials FILE),
    and report what to know before a class: the connection, the state's rate, the joints,
    the plant's clock and, with video:, the camera's frames/s and age. It never takes the
    lease. Exit status 1 when a check fails."""


def add_parser(sub: Any) -> None:
    """Add ``plant`` (with ``serve`` and ``check``) to ``ejsgen``'s subparsers."""
    p = sub.add_parser("plant", help="run the reference plant of a remote lab, or check a spec's plant: section against a live plant",
                       description=_DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    ps = p.add_subparsers(dest="plant_command", required=True)
    ps.add_parser("serve", add_help=False, help="run the reference plant (ejsgen plant serve --help lists its options)",
                  description="Run the reference plant; the options are python -m ejsrl.plant's.")
    c = ps.add_parser("check", help="check SPEC's plant: section against the live plant it names",
                      description="Validate SPEC, connect to its plant as the app would (never taking the lease) and report "
                      "the connection, the state's rate, the joints, the plant's clock and the camera. Exit 1 when a check fails.")
    c.add_argument("spec", metavar="SPEC")
    c.add_argument("--timeout", type=float, default=15.0, metavar="S", help="how long to wait for the plant (default 15 s)")
    c.add_argument("--listen", type=float, default=2.0, metavar="S", help="how long to measure the state and the video (default 2 s)")
    c.add_argument("--credentials", metavar="FILE", help="username/password/TLS settings (as EJSRL_PLANT_CREDENTIALS=FILE)")


def serve(argv: list[str]) -> int:
    """``ejsgen plant serve ARGS``: the reference plant with ARGS untouched (``--help`` included)."""
    from ejsrl.plant.__main__ import main

    return main(argv, prog="ejsgen plant serve")


def cmd_plant(args: argparse.Namespace) -> int:
    if args.plant_command == "check":
        return check(Path(args.spec), timeout=args.timeout, listen=args.listen, credentials=args.credentials)
    raise EjsError("ejsgen plant: give serve or check")  # pragma: no cover - argparse requires one


def _plant_section(spec: Path) -> Any:
    """Validate and compile ``spec`` (raising its errors at FILE:LINE:COL); its ``plant:`` model."""
    from ejsgen.compiler import compile_spec
    from ejsgen.validate import validate
    from ejsgen.yamlload import load_yaml

    doc = load_yaml(spec, display_name=str(spec))
    checked = validate(doc)
    compile_spec(checked, spec.resolve())
    plant = checked.spec.plant
    if plant is None:
        raise SpecError(doc.loc(()), "this spec has no plant: section",
                        "add one to link the lab to a real plant (specs/language.md, Remote laboratories)")
    return plant


def _connect(plant: Any, credentials: str | None) -> tuple[Any, str]:
    """A link to the plant named by the ``plant:`` model, the way the app connects; and its address."""
    from ejsrl.app._plant_link import PlantDef

    if credentials:
        if not os.path.isfile(credentials):
            raise EjsError(f"--credentials {credentials}: no such file")
        os.environ["EJSRL_PLANT_CREDENTIALS"] = credentials
    defn = PlantDef(plant.host, plant.port, topic=plant.topic, heartbeat=plant.heartbeat, transport=plant.transport)
    host = os.environ.get("EJSRL_PLANT_HOST") or plant.host
    port = os.environ.get("EJSRL_PLANT_PORT") or plant.port
    where = (f"mqtt://{host}:{port} (topic {plant.topic})" if plant.transport == "mqtt"
             else f"opc.tcp://{host}:{port}/ejsrl/plant/")
    try:
        return defn.connect(), where
    except (OSError, ValueError) as e:     # a bad credentials file, an unknown host
        raise EjsError(f"cannot reach the plant at {where}: {e}") from None


def check(spec: Path, *, timeout: float = 15.0, listen: float = 2.0, credentials: str | None = None) -> int:
    """Run the checks; print one line each (``ok``/``FAIL``) and return the exit status."""
    plant = _plant_section(spec)
    print(f"{spec}: plant: section ok")
    link, where = _connect(plant, credentials)
    failed = 0

    def say(ok: bool, text: str) -> None:
        nonlocal failed
        failed += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {text}", flush=True)

    try:
        if not link.wait_for(lambda l: l.connected, timeout):
            say(False, f"no connection to {where} in {timeout:g} s: {link.note}")
            return 1
        say(True, f"connected to {where}")
        if not link.wait_for(lambda l: l.state is not None, timeout):
            say(False, f"the plant sends no state on {where} ({link.note}): is it running? (ejsgen plant serve ...)")
            return 1
        if plant.video is not None:
            link.want_video(True)
        n0, t0 = link.states, time.monotonic()
        time.sleep(listen)
        st = link.state or {}
        rate = (link.states - n0) / (time.monotonic() - t0)
        say(link.plant_online and rate > 0, f"the plant is online: boot {st.get('boot')}, status {st.get('status')}, "
            f"{rate:.0f} states/s, e-stop {'ON' if st.get('estop') else 'off'}, holder {'someone' if st.get('holder') else 'none'}, "
            f"{len(st.get('queue') or [])} waiting")
        q = st.get("q") or []
        if any(c.to == "joints" for c in plant.commands.values()):
            say(len(q) == 5, f"the plant measures {len(q)} joints; the lab commands 5")
        if link.clock.offset is not None:
            print(f"     the plant's clock is {0.0 + round(-link.clock.offset, 3):+.3f} s from this machine's (transit included)")
        if plant.video is not None:
            _check_video(link, plant.video.stale, listen, say)
        if st.get("fault"):
            say(False, f"the plant reports a fault: {st['fault']}")
    finally:
        link.close()
    print(f"{spec}: {'all checks passed' if not failed else f'{failed} check(s) failed'}")
    return 1 if failed else 0


def _check_video(link: Any, stale: float, listen: float, say: Any) -> None:
    if not link.wait_for(lambda l: l.frame is not None, max(listen, 5.0)):
        say(False, f"no camera frame from the plant in {max(listen, 5.0):g} s (video: is in the spec; "
            f"is the plant's camera on? ejsgen plant serve --camera 320x240)")
        return
    n0, t0, ages = link.frames, time.monotonic(), []
    end = t0 + listen
    while time.monotonic() < end:
        seq = link.frame.seq
        if link.wait_for(lambda l: l.frame.seq != seq, end - time.monotonic()):
            ages.append(link.video_age())
    fps = (link.frames - n0) / (time.monotonic() - t0)
    f = link.frame
    if not ages:
        say(False, f"the camera's frames stopped (the newest is {link.video_age():.1f} s old)")
        return
    ages.sort()
    median = ages[len(ages) // 2]
    say(median <= stale, f"camera: {f.w} x {f.h} JPEG, {fps:.1f} frames/s, age {median * 1000:.0f} ms median "
        f"(stale past {stale * 1000:.0f} ms){'' if not link.bad_frames else f', {link.bad_frames} bad frames dropped'}")
