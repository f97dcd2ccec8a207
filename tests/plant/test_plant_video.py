"""The plant's camera stream (issue #26): frames rendered by the reference plant, carried by real
servers (mosquitto, the plant's asyncua server) and checked by the app's link; their age on the
app's clock against a plant whose clock is offset, a plant paused with SIGSTOP and one killed."""

from __future__ import annotations

import math
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from testkit.plant import Broker, PlantProc, free_port

DEG = math.pi / 180
OFFSET = 1000.0            # the plant's clock runs this many seconds ahead of the app's


def _decode(jpeg: bytes) -> np.ndarray:
    import cv2

    img = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR)
    assert img is not None, "OpenCV could not decode the frame"
    return img[:, :, ::-1]


def _arm_centroid(rgb: np.ndarray) -> np.ndarray:
    """The centre (u, v) of the arm's orange pixels (the robot colour #e8892c, shaded)."""
    r, g, b = (rgb[..., i].astype(int) for i in range(3))
    mask = (r > 120) & (r - b > 90) & (g > 0.35 * r) & (g < 0.8 * r) & (b < 100)
    assert mask.sum() > 100, "no arm in the picture"
    v, u = np.nonzero(mask)
    return np.array([u.mean(), v.mean()])


def _project(p_world: np.ndarray, w: int, h: int) -> np.ndarray:
    """Pixel (u, v) of a world point for the plant's camera, by a pinhole model written here:
    eye (1.1, -0.9, 0.85) looking at (0, 0, 0.3), z up, vertical field of view 50 deg."""
    eye, target = np.array([1.1, -0.9, 0.85]), np.array([0.0, 0.0, 0.3])
    z = (target - eye) / np.linalg.norm(target - eye)
    x = np.cross(z, [0, 0, 1.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pc = np.array([x, y, z]) @ (p_world - eye)
    f = (h / 2) / math.tan(math.radians(50) / 2)
    return np.array([w / 2 + f * pc[0] / pc[2], h / 2 + f * pc[1] / pc[2]])


def _next_frame(link, timeout: float = 20.0):
    seq = link.frame.seq if link.frame else 0
    assert link.wait_for(lambda l: l.frame is not None and l.frame.seq != seq, timeout), f"no new frame ({link.note})"
    return link.frame


def test_frames_arrive_decode_and_show_the_arm_where_its_encoders_say(broker: Broker, tmp_path: Path, link_factory) -> None:
    from ejsrl.plant import Arm

    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--camera", "320x240", "--fps", "10", "--noise", "0"])
    try:
        link = link_factory(session="viewer")
        assert link.frame is None                  # no video until asked for (a Simulation-mode page)
        link.want_video(True)
        f0 = _next_frame(link)
        assert (f0.w, f0.h) == (320, 240)
        img0 = _decode(f0.jpeg)
        assert img0.shape == (240, 320, 3)
        c0 = _arm_centroid(img0)
        # frames come at the camera's rate: 10 a second, give or take a loaded machine
        n0, t0 = link.frames, time.monotonic()
        time.sleep(2.0)
        rate = (link.frames - n0) / (time.monotonic() - t0)
        assert 3.0 < rate <= 11.0, rate
        # turn joint 1 by 90 deg and lift the arm: the arm in the picture moves the way a pinhole
        # projection of the tool (its forward kinematics) says
        link.request_lease()
        assert link.wait_for(lambda l: l.holds_lease, 20)
        target = np.array([90, 40, 0, 0, 0]) * DEG
        assert link.send(target) is None
        assert link.wait_for(lambda l: np.max(np.abs(l.measured() - target)) < 0.5 * DEG and l.state["status"] == "idle", 30)
        _next_frame(link)
        c1 = _arm_centroid(_decode(_next_frame(link).jpeg))
        arm = Arm()
        tip0, tip1 = (_project(arm.tool_position(q), 320, 240) for q in (np.zeros(5), target))
        moved, predicted = c1 - c0, tip1 - tip0
        assert np.linalg.norm(moved) > 15, (c0, c1)
        assert moved @ predicted / (np.linalg.norm(moved) * np.linalg.norm(predicted)) > 0.7, (moved, predicted)
        # unsubscribed: no more frames reach this session
        link.want_video(False)
        time.sleep(0.5)
        n = link.frames
        time.sleep(1.0)
        assert link.frames == n
    finally:
        plant.stop()


def test_age_is_on_the_apps_clock_for_a_plant_with_another_clock_and_grows_when_it_pauses(
        broker: Broker, tmp_path: Path, link_factory) -> None:
    """The plant's clock is 1000 s ahead and its camera pipeline delays frames by 0.3 s: the age
    the link shows agrees with the true age (the plant runs on this machine, so its clock minus
    the known offset is ours). SIGSTOP freezes the plant: the age grows with the wall clock."""
    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--clock-offset", str(OFFSET),
                                 "--video-latency", "0.3", "--fps", "10"])
    try:
        link = link_factory()
        link.want_video(True)
        _next_frame(link)
        for _ in range(5):
            f = _next_frame(link)
            now = time.monotonic()
            age, true_age = link.video_age(now), now - (f.t - OFFSET)
            # the link's age is the true one to within the fastest transit of a state message
            assert abs(age - true_age) < 0.02, (age, true_age)
            assert 0.3 <= true_age < 1.0, true_age
        # the plant freezes (a hung controller): no frame, no state; the age keeps growing
        plant.proc.send_signal(signal.SIGSTOP)
        paused = time.monotonic()
        try:
            time.sleep(0.3)
            last = link.frame
            time.sleep(1.5)
            assert link.frame is last or link.frame.seq == last.seq + 1  # at most one that was in flight
            age = link.video_age()
            assert age >= time.monotonic() - paused, age
        finally:
            plant.proc.send_signal(signal.SIGCONT)
        # awake again: the frames held in its camera's pipeline come first, as old as they are,
        # then fresh ones
        f = _next_frame(link)
        assert time.monotonic() - (f.t - OFFSET) > 1.5
        assert link.wait_for(lambda l: l.video_age() < 1.0, 10), link.video_age()
        assert link.video_age() >= 0.3
    finally:
        plant.stop()


def test_a_killed_plant_leaves_a_growing_age_and_a_restarted_one_counts_again(broker: Broker, tmp_path: Path, link_factory) -> None:
    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--clock-offset", "-5000"])
    link = link_factory()
    link.want_video(True)
    _next_frame(link)
    assert link.video_age() < 1.0
    plant.proc.send_signal(signal.SIGKILL)
    plant.proc.wait(10)
    killed = time.monotonic()
    assert link.wait_for(lambda l: not l.plant_online, 20)     # its last will, at once
    time.sleep(1.0)
    assert link.video_age() >= time.monotonic() - killed
    # a new plant (another boot, another clock): its frames count from its own clock
    again = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--clock-offset", "7000"])
    try:
        assert link.wait_for(lambda l: l.frame is not None and l.frame.boot == l.state["boot"], 30)
        _next_frame(link)
        assert link.video_age() < 1.0
    finally:
        again.stop()


def test_the_link_refuses_what_is_not_a_whole_frame(broker: Broker, plant: PlantProc, link_factory) -> None:
    """Anything on the video topic that is not a header line and a whole JPEG of that size is
    counted and dropped, never shown (the page gets only what the link kept)."""
    import paho.mqtt.client as mqtt

    from ejsrl.plant._video import jpeg_size, pack_frame, parse_frame

    link = link_factory()
    link.want_video(True)
    good = _next_frame(link)
    w, h = jpeg_size(good.jpeg)
    assert (w, h) == (good.w, good.h)
    bad = [
        b"<script>alert(1)</script>",
        pack_frame(good.jpeg[:-200], t=good.t, seq=99, w=w, h=h, boot=good.boot),           # truncated
        pack_frame(good.jpeg, t=good.t, seq=99, w=w * 2, h=h, boot=good.boot),              # size lies
        pack_frame(b"\xff\xd8" + b"\x00" * 50 + b"\xff\xd9", t=good.t, seq=99, w=w, h=h, boot=good.boot),
        b'{"t": NaN, "seq": 1, "w": 320, "h": 240}\n' + good.jpeg,
        b"x" * (2 << 20),
    ]
    for payload in bad:
        assert isinstance(parse_frame(payload, 0.0), str)
    other = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id="intruder")
    other.connect("127.0.0.1", broker.port)
    other.loop_start()
    try:
        plant.proc.send_signal(signal.SIGSTOP)       # only the intruder's frames now
        time.sleep(0.3)
        kept, refused = link.frame, link.bad_frames
        for payload in bad:
            other.publish("ejsrl/plant/video", payload, qos=1).wait_for_publish(5)
        assert link.wait_for(lambda l: l.bad_frames >= refused + len(bad), 10), link.bad_frames
        assert link.frame is kept
    finally:
        plant.proc.send_signal(signal.SIGCONT)
        other.loop_stop()


def test_frames_over_opcua_with_the_same_age(tmp_path: Path) -> None:
    from ejsrl.app._plant_opcua import OpcUaLink

    port = free_port()
    plant = PlantProc(tmp_path, ["--opcua", f"127.0.0.1:{port}", "--clock-offset", str(OFFSET), "--video-latency", "0.2"])
    link = OpcUaLink("127.0.0.1", port)
    try:
        assert link.wait_for(lambda l: l.state is not None, 60), link.note
        link.want_video(True)
        _next_frame(link, 30)
        for _ in range(3):
            f = _next_frame(link)
            now = time.monotonic()
            assert _decode(f.jpeg).shape == (240, 320, 3)
            true_age = now - (f.t - OFFSET)
            # polled 50 times a second: the frame is at most one poll older than when it came
            assert abs(link.video_age(now) - true_age) < 0.05, (link.video_age(now), true_age)
            assert 0.2 <= true_age < 1.0
        plant.proc.send_signal(signal.SIGKILL)
        plant.proc.wait(10)
        assert link.wait_for(lambda l: not l.connected, 30)
        time.sleep(1.0)
        assert link.video_age() > 1.0
    finally:
        link.close()
        plant.stop()


@pytest.mark.parametrize("text", ["640x", "big", "10x10"])
def test_the_plant_refuses_a_bad_camera_size(tmp_path: Path, text: str) -> None:
    import subprocess
    import sys

    r = subprocess.run([sys.executable, "-m", "ejsrl.plant", "--mqtt", "127.0.0.1:1", "--camera", text],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and ("--camera" in r.stderr or "16..1920" in r.stderr), r.stderr


class _Handle:
    """A GUI element as the plant panel uses it (viser's handles: value, visible, label, content)."""

    def __init__(self, **kw) -> None:
        self.visible, self.label, self.content, self.value = True, "", "", None
        self.__dict__.update(kw)
        self.sent: list[bytes] = []

    def __setattr__(self, name: str, value) -> None:
        if name == "_data":
            self.sent.append(value)
        object.__setattr__(self, name, value)

    def on_update(self, fn):
        return fn

    on_click = on_update


class _Gui:
    def __init__(self) -> None:
        self.image: _Handle | None = None

    def add_dropdown(self, label, options, initial_value, hint=None):
        return _Handle(value=initial_value)

    def add_button(self, label, color=None, hint=None, visible=True):
        return _Handle(visible=visible)

    def add_markdown(self, content):
        return _Handle(content=content)

    def add_image(self, image, label=None, format="jpeg", visible=True):
        self.image = _Handle(label=label, visible=visible)
        return self.image


def test_the_panel_sends_at_most_its_rate_shows_the_age_and_flags_a_paused_plant_stale(
        broker: Broker, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The plant streams 30 frames/s; a page asks for 5 (video: {rate: 5}): the panel sends the
    plant's own JPEG bytes at most 5 times a second, only in Real plant mode, and writes the age."""
    import re
    import types

    from ejsrl.app._plant_link import PlantDef, PlantMeasurement
    from ejsrl.plant._panel import PlantPanel

    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--fps", "30"])
    monkeypatch.setenv("EJSRL_PLANT_PORT", str(broker.port))
    defn = PlantDef("127.0.0.1", 1, video_stale=0.5, video_rate=5.0, measurements=[PlantMeasurement("age_ms", "video_age", scale=1e-3)])
    model = types.SimpleNamespace(_plant=lambda: defn, age_ms=0.0)
    gui = _Gui()
    panel = PlantPanel(gui, types.SimpleNamespace(model=model))
    try:
        assert panel.link.wait_for(lambda l: l.state is not None, 30), panel.link.note

        def run(seconds: float) -> None:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                panel.refresh()          # the app's frames, 60 a second
                time.sleep(1 / 60)

        run(1.0)
        assert gui.image.sent == [] and not gui.image.visible and "Video" not in panel.status.content  # Simulation mode
        panel.set_real(True)
        assert panel.link.wait_for(lambda l: l.frame is not None, 20)
        n0, t0 = len(gui.image.sent), time.monotonic()
        run(3.0)
        sent = len(gui.image.sent) - n0
        assert 3 <= sent <= 5 * (time.monotonic() - t0) + 1, sent
        assert gui.image.visible and gui.image.sent[-1][:2] == b"\xff\xd8" and gui.image.sent[-1][-2:] == b"\xff\xd9"
        m = re.search(r"\*\*Video:\*\* (\d+) ms old", panel.status.content)
        assert m and int(m.group(1)) < 1000, panel.status.content
        assert 0 < model.age_ms < 1000
        plant.proc.send_signal(signal.SIGSTOP)
        try:
            run(1.5)
            assert "**Video: STALE** (the newest frame is" in panel.status.content, panel.status.content
            assert gui.image.label == "Plant camera: STALE" and model.age_ms > 1000
            n = len(gui.image.sent)
            run(0.5)
            assert len(gui.image.sent) == n          # nothing new to send
        finally:
            plant.proc.send_signal(signal.SIGCONT)
        assert panel.link.wait_for(lambda l: l.video_age() < 0.5, 20)
        run(0.5)
        assert gui.image.label == "Plant camera" and "STALE" not in panel.status.content
        panel.set_real(False)
        assert not gui.image.visible and not panel.link.video_wanted
    finally:
        panel.close()
        plant.stop()


@pytest.mark.parametrize("progressive", [False, True])
def test_jpeg_size_agrees_with_opencv(progressive: bool) -> None:
    """The app reads a frame's size from its JPEG header without decoding it: the same size
    OpenCV decodes, for baseline and progressive JPEGs; a cut or padded one is refused."""
    import cv2

    from ejsrl.plant._video import jpeg_size

    rng = np.random.default_rng(3)
    for w, h in ((16, 16), (320, 240), (641, 479), (1920, 1080)):
        img = rng.integers(0, 255, (h, w, 3), dtype=np.uint8)
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 70, cv2.IMWRITE_JPEG_PROGRESSIVE, int(progressive)])
        data = buf.tobytes()
        decoded = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        assert jpeg_size(data) == (decoded.shape[1], decoded.shape[0]) == (w, h)
        assert jpeg_size(data[:-1]) is None and jpeg_size(data + b"\x00") is None and jpeg_size(data[:600]) is None


def test_plant_clock_takes_the_fastest_transit_and_follows_a_drifting_clock() -> None:
    """Arrivals of a plant's stamps with random transit (0.2 ms to 30 ms) and a clock 1234.5 s
    ahead: the offset is the true one plus the fastest transit; a plant clock that drifts 100 ppm
    is followed within the window; a restart (reset) forgets the old clock."""
    from ejsrl.plant._video import PlantClock

    rng = np.random.default_rng(1)
    clock = PlantClock(window=30.0)
    true_offset = -1234.5          # local = plant + offset
    for k in range(50 * 20):       # 20 s of 50 Hz states
        local = 100.0 + k * 0.02
        transit = 0.0002 + rng.exponential(0.005)
        clock.add(local - true_offset - transit, local)
    assert clock.offset is not None and 0 <= clock.offset - true_offset < 0.001
    assert abs(clock.age(50.0, 200.0) - (200.0 - (50.0 + true_offset))) < 0.001
    for k in range(50 * 120):      # two more minutes, the plant's clock running 100 ppm slow
        local = 120.0 + k * 0.02
        clock.add(local - true_offset - 1e-4 * (local - 120.0) - 0.0002, local)
    assert abs(clock.offset - (true_offset + 1e-4 * 120.0 + 0.0002)) < 0.004   # within 30 s of drift (3 ms)
    clock.reset()
    assert clock.offset is None and clock.age(1.0) is None
    clock.add(float("nan"), 1.0)
    clock.add("x", 1.0)
    assert clock.offset is None
