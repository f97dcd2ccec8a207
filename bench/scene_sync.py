"""What drawing the 3D view's lines by poses costs: messages a tab receives per 5 s of play and the
server's CPU, for labs with lines, trails, point clouds and arrows, this runtime against another.

    python bench/scene_sync.py --before /path/to/other/import/root   # side by side, interleaved
    python bench/scene_sync.py                                        # this runtime alone

``--before`` is a folder that holds another ``ejsrl`` (and the ``ejsgen`` that built its apps) to
import first: e.g. ``git archive <commit> ejsgen templates specs runtime`` laid out as installed
(``ejsgen/``, ``ejsgen/templates``, ``ejsgen/specs``, ``ejsrl/``). Each lab's ``app.py`` serves
in its own process (a simulation per tab); one raw websocket client presses Play, waits 2 s, and
counts every message it receives for ``--seconds`` (scaled to 5 s); the server's CPU is its
process tree's user + system time over the same span. Runs alternate (before, after, before,
after) and the load average is printed beside every figure. The lag each drawing leaves is
measured in real browsers by tests/browser/test_line_sync_browser.py and test_view3d_browser.py.
"""

from __future__ import annotations

import argparse
import asyncio
import collections
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # testkit.guard_client: the raw viser client
sys.path.insert(0, str(ROOT / "bench"))

sys.path.insert(0, str(ROOT / "tests" / "browser"))

from classroom import Server  # noqa: E402  (the lab's app.py in its own process)
from test_line_sync_browser import LAB  # noqa: E402

#: the browser test's lab (a zigzag spring on an oscillating plate, a ball on an ellipse with its
#: trail) with a velocity arrow on the plate; paused at first (the client presses Play)
SPRING_TRAIL = LAB.replace("simulation: {fps: 30, autoplay: true}", """\
      - arrow: {name: velocity, start: [x, 0, -0.2], vector: ["0.2*v", 0, 0], width: 0.01, color: "#00a000"}
simulation: {fps: 30, autoplay: false}""")

LABS = {
    "pendulum": ROOT / "examples" / "pendulum.ejs.yaml",
    "mass_spring_chain": ROOT / "examples" / "mass_spring_chain.ejs.yaml",
    "spring_trail_arrow": None,
}


def build(name: str, root: Path, import_root: str | None) -> Path:
    """Build the lab with the ``ejsgen`` under ``import_root`` (this one if None), in a child process."""
    spec = LABS[name]
    if spec is None:
        spec = root / f"{name}.ejs.yaml"
        spec.write_text(SPRING_TRAIL)
    out = root / f"{name}-{'before' if import_root else 'after'}"
    env = _env(import_root)
    subprocess.run([sys.executable, "-P", "-c", f"from ejsgen.cli import build; build({str(spec)!r}, {str(out)!r})"], check=True, env=env)
    return out


def _env(import_root: str | None) -> dict[str, str]:
    env = dict(os.environ)
    if import_root:
        env["PYTHONPATH"] = import_root + os.pathsep + env.get("PYTHONPATH", "")
    return env


async def _count(port: int, seconds: float) -> collections.Counter:
    from testkit.guard_client import Client, gui_update

    client = await Client.open(port)
    await client.until(lambda: any(m.get("type") == "GuiButtonMessage" and m["props"].get("label") == "Play" for m in client.received),
                       "the panel", timeout=120)
    play = next(m["uuid"] for m in client.received if m.get("type") == "GuiButtonMessage" and m["props"].get("label") == "Play")
    await client.send(gui_update(play, value=True))
    await asyncio.sleep(2.0)
    start = len(client.received)
    await asyncio.sleep(seconds)
    got = collections.Counter(m.get("type", "?") for m in client.received[start:])
    await client.close()
    return got


def measure(app_dir: Path, import_root: str | None, seconds: float) -> tuple[collections.Counter, float]:
    """(messages by type per 5 s, server CPU seconds per second) for one tab playing the lab."""
    old = os.environ.get("PYTHONPATH")
    if import_root:
        os.environ["PYTHONPATH"] = import_root + os.pathsep + (old or "")
    try:
        server = Server(app_dir, processes=1)
    finally:
        if import_root:
            if old is None:
                os.environ.pop("PYTHONPATH", None)
            else:
                os.environ["PYTHONPATH"] = old
    try:
        cpu0, wall0 = server.cpu_seconds(), time.perf_counter()
        got = asyncio.run(_count(server.port, seconds))
        cpu = (server.cpu_seconds() - cpu0) / (time.perf_counter() - wall0)
    finally:
        server.stop()
    scale = 5.0 / seconds
    return collections.Counter({k: round(v * scale) for k, v in got.items()}), cpu


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", help="an import root with the other ejsrl/ejsgen (see the module's docstring)")
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--labs", default=",".join(LABS))
    args = parser.parse_args(argv)
    root = Path(tempfile.mkdtemp(prefix="scene-sync-"))
    sides = ([("before", args.before)] if args.before else []) + [("after", None)]
    print(f"{'lab':20} {'runtime':7} {'msgs/5 s':>9} {'scene':>6} {'poses':>6} {'points':>7} {'cpu %':>6}  load")
    for name in args.labs.split(","):
        apps = {side: build(name, root, where) for side, where in sides}
        for _ in range(args.rounds):
            for side, where in sides:
                got, cpu = measure(apps[side], where, args.seconds)
                poses = got["SetPositionMessage"] + got["SetOrientationMessage"]
                scene = poses + got["SceneNodeUpdateMessage"] + got["SetSceneNodeVisibilityMessage"]
                print(f"{name:20} {side:7} {sum(got.values()):9d} {scene:6d} {poses:6d} {got['SceneNodeUpdateMessage']:7d} "
                      f"{100 * cpu:6.1f}  {os.getloadavg()[0]:.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
