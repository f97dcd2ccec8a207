"""Fair share under a hostile client (issue #30), with real clients: the six-axis arm of
the paper served as a teacher serves it (``python app.py``, one serving process), three
students playing their own simulations, and a script that sends 2,000 joint values a
second (each runs the lab's on_change code: forward kinematics), then also opens 40 more
connections to its live session address. The students must keep their frame rate and
their controls must answer; the teacher's terminal must not fill up.

Without the pacing of ``ejsrl.view._fair`` the students fell from 28 to 18 frames/s and
their controls answered in up to 0.4 s (``bench/classroom.py --flood``, a loaded machine).
Frame rates are compared with the same students' quiet rate on the same machine, so that
other work on the machine does not decide the test.

Bounded: one process, 44 connections, about 40 s in all, loopback only."""

from __future__ import annotations

import asyncio
import math
import statistics
import time

import msgspec
import pytest

from testkit.classroom import FULL, join, readouts, token_of
from testkit.guard_client import CAMERA, Client, gui_update, run_async
from testkit.served import Served

LAB = "paper/six_axis_kinematics"
STUDENTS = 3
FLOOD_RATE = 2000.0  # values a second
LIVE_COPIES = 40
MEASURE_SECONDS = 5.0


def button(client: Client) -> str:
    return next(m["uuid"] for m in client.received if m.get("type") == "GuiButtonMessage"
                and m["props"]["label"] in ("Play", "Pause"))


def labels_of(client: Client, uuid: str) -> list[str]:
    return [m["updates"]["label"] for m in client.seen("GuiUpdateMessage", uuid=uuid) if "label" in m["updates"]]


async def student(port: int, cookie: str | None, path: str = "") -> Client:
    return await join(port, path, cookie, timeout=90)


async def frames_per_second(clients: list[Client], seconds: float) -> list[float]:
    before = [len(readouts(c)) for c in clients]
    await asyncio.sleep(seconds)
    return [(len(readouts(c)) - b) / seconds for c, b in zip(clients, before)]


async def response_times(client: Client, presses: int = 4) -> list[float]:
    """Seconds from pressing Play/Pause to the button being relabelled, ``presses`` times."""
    uuid = button(client)
    out = []
    for _ in range(presses):
        seen = len(labels_of(client, uuid))
        t = time.monotonic()
        await client.send(gui_update(uuid, value=True))
        await client.until(lambda: len(labels_of(client, uuid)) > seen, "the button to answer", timeout=20)
        out.append(time.monotonic() - t)
        await asyncio.sleep(0.1)
    return out


@pytest.fixture(scope="module")
def served(built, tmp_path_factory):
    server = Served(built(LAB), tmp_path_factory.mktemp("fair"), "--processes", "1", "--max-sessions", "12")
    yield server
    server.stop()


def test_a_flood_and_copies_of_a_live_address_do_not_slow_the_other_students(served):
    async def scenario() -> dict[str, object]:
        students = [await student(served.port, f"student-browser-{i:04d}") for i in range(STUDENTS)]
        for s in students:
            await s.send(gui_update(button(s), value=True))  # Play
        await asyncio.sleep(1.5)
        quiet_fps = await frames_per_second(students, MEASURE_SECONDS)
        quiet_rt = await response_times(students[0])

        evil = await student(served.port, None)
        sliders = [m["uuid"] for m in evil.received if m.get("type") == "GuiSliderMessage"][:2]
        evil_token = token_of(evil)
        stop = asyncio.Event()
        sent = 0

        async def flood() -> None:
            nonlocal sent
            start = time.monotonic()
            while not stop.is_set():
                due = int((time.monotonic() - start) * FLOOD_RATE)
                while sent < due:  # two joints' values in turn, every one a new value
                    message = gui_update(sliders[sent % 2], value=float(sent % 180) / 2)
                    await evil.ws.send(msgspec.msgpack.encode(message))
                    sent += 1
                await asyncio.sleep(0.005)

        flooding = asyncio.create_task(flood())
        await asyncio.sleep(1.0)
        flood_fps = await frames_per_second(students, MEASURE_SECONDS)
        flood_rt = await response_times(students[0]) + await response_times(students[1])
        # 40 connections to the flooder's live address, each registering like a page does: a reload
        # waiting for its old connection must hold no thread another session needs
        copies = []
        for _ in range(LIVE_COPIES):
            c = await Client.open(served.port, path=f"/s/{evil_token}", camera=False)
            await c.send(CAMERA)
            copies.append(c)
        # measured once they are settled: each waits up to 2 s for the address's tab to close,
        # holding no thread, then gets a lab of its own while places are left (max-sessions
        # 12), else the "lab is full" page; making those labs is a one-off cost of new tabs
        await Client.until(lambda: all(token_of(c) is not None or FULL in " ".join(c.texts())
                                       for c in copies), "the copies to be settled", timeout=90)
        await asyncio.sleep(1.0)
        loud_fps = await frames_per_second(students, MEASURE_SECONDS)
        loud_rt = await response_times(students[0]) + await response_times(students[1])
        new_tab = time.monotonic()
        late = await student(served.port, "student-browser-late")
        new_tab = time.monotonic() - new_tab
        stop.set()
        await flooding
        flood_seconds = sent / FLOOD_RATE
        for c in [*students, evil, *copies, late]:
            await c.close()
        return dict(quiet_fps=quiet_fps, quiet_rt=quiet_rt, flood_fps=flood_fps, flood_rt=flood_rt,
                    loud_fps=loud_fps, loud_rt=loud_rt, sent=sent,
                    flood_seconds=flood_seconds, new_tab=new_tab)

    r = run_async(scenario(), timeout=240)
    print(f"\nquiet: {r['quiet_fps']} frames/s, controls {max(r['quiet_rt']):.3f} s; a flood of {r['sent']} values "
          f"in {r['flood_seconds']:.1f} s: {r['flood_fps']} frames/s, controls max {max(r['flood_rt']):.3f} s; "
          f"+ {LIVE_COPIES} copies of a live address: {r['loud_fps']} frames/s, "
          f"controls median {statistics.median(r['loud_rt']):.3f} s max {max(r['loud_rt']):.3f} s, "
          f"a new tab {r['new_tab']:.2f} s")
    assert r["sent"] >= 0.8 * FLOOD_RATE * 2 * MEASURE_SECONDS  # the flood really ran at its rate
    # >= 27 frames/s, or on a machine too busy for that even when quiet, >= 90 % of the quiet rate
    floor = min(27.0, 0.9 * min(r["quiet_fps"]))
    assert min(r["flood_fps"]) >= floor, (r["quiet_fps"], r["flood_fps"])
    assert min(r["loud_fps"]) >= floor, (r["quiet_fps"], r["loud_fps"])
    assert max(r["flood_rt"] + r["loud_rt"]) <= 0.3, (r["flood_rt"], r["loud_rt"])
    # a new tab is answered at once (its panel, or "full" once the copies took the places left)
    assert r["new_tab"] < 3.0


def test_hostile_messages_add_little_to_the_teachers_terminal(served):
    """2,000 messages with bad UTF-8, a value of 1e308 (clamped, as documented), the text
    "2.0" for a slider (refused), unknown kinds: at most 20 KB of log in all."""
    before = served.err.stat().st_size + served.out.stat().st_size

    async def scenario() -> tuple[Client, str]:
        evil = await student(served.port, None)
        slider = next(m["uuid"] for m in evil.received if m.get("type") == "GuiSliderMessage")
        good = msgspec.msgpack.encode(gui_update(slider, value=1.5))
        bad_utf8 = good.replace(slider.encode()[:4], b"\xff\xfe\xfd\xfc")
        for i in range(500):
            await evil.ws.send(bad_utf8)
            await evil.ws.send(msgspec.msgpack.encode(gui_update(slider, value=1e308)))
            await evil.ws.send(msgspec.msgpack.encode(gui_update(slider, value="2.0")))
            await evil.ws.send(msgspec.msgpack.encode({"type": f"Nonsense{i}Message"}))
        await evil.send(gui_update(slider, value=1e308))
        await evil.until(lambda: 180.0 in evil.values_of(slider), "1e308 to be clamped to the maximum 180", timeout=30)
        await evil.until(lambda: any("Value refused" in n and "2.0" in n for n in evil.notifications()),
                         "the text to be refused", timeout=30)
        assert evil.closed is None  # the connection carries on
        await evil.close()
        return evil, slider

    evil, slider = run_async(scenario(), timeout=120)
    time.sleep(0.5)
    added = served.err.stat().st_size + served.out.stat().st_size - before
    print(f"\n2,000 hostile messages added {added} bytes of log")
    assert added <= 20_000, (served.err.read_text()[-3000:])
    assert "Traceback" not in served.err.read_text()
    assert all(math.isfinite(v) and v <= 180.0 for v in evil.values_of(slider))
