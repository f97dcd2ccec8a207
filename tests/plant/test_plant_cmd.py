"""``ejsgen plant``: the reference plant served by ``ejsgen plant serve`` on a real mosquitto, and
``ejsgen plant check SPEC`` run as a user runs it (a child process) against it."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from testkit import EXAMPLES
from testkit.plant import Broker, PlantProc, free_port


def _ejsgen(*args: str, env: dict[str, str] | None = None, timeout: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ejsgen.cli", *args], capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, **(env or {})})


class _Served(PlantProc):
    """``ejsgen plant serve ARGS`` as a child process (it prints ``ready`` as the plant does)."""

    def __init__(self, tmp: Path, args: list[str]) -> None:
        import time

        self.out_path, self.err_path = tmp / "serve.out", tmp / "serve.err"
        self.proc = subprocess.Popen([sys.executable, "-m", "ejsgen.cli", "plant", "serve", *args],
                                     stdout=open(self.out_path, "wb"), stderr=open(self.err_path, "wb"))
        end = time.monotonic() + 60
        while b"ready" not in self.out_path.read_bytes():
            assert self.proc.poll() is None and time.monotonic() < end, self.err_path.read_text()
            time.sleep(0.05)


def test_serve_then_check_the_robualab_spec_against_it(broker: Broker, tmp_path: Path) -> None:
    plant = _Served(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--clock-offset", "-42", "--fps", "10"])
    spec = tmp_path / "robualab.ejs.yaml"      # a loaded test machine may take more than half a second
    spec.write_text((EXAMPLES / "paper" / "robualab.ejs.yaml").read_text().replace("video: {stale: 0.5}", "video: {stale: 3}"))
    try:
        r = _ejsgen("plant", "check", str(spec), "--listen", "2", env={"EJSRL_PLANT_PORT": str(broker.port)})
        assert r.returncode == 0, r.stdout + r.stderr
        out = r.stdout
        assert f"ok   connected to mqtt://127.0.0.1:{broker.port} (topic ejsrl/plant)" in out
        assert "ok   the plant is online" in out and "status idle" in out and "holder none" in out
        assert "ok   the plant measures 5 joints; the lab commands 5" in out
        # the plant's clock, 42 s behind this machine's: its offset is said to the ms (loopback transit)
        assert "the plant's clock is -42.00" in out, out
        assert "ok   camera: 320 x 240 JPEG" in out and "all checks passed" in out
        fps = float(out.split("JPEG, ")[1].split(" frames/s")[0])
        assert 3.0 <= fps <= 11.0, fps
    finally:
        plant.stop()


def test_check_fails_without_a_plant_and_names_a_stopped_camera(broker: Broker, tmp_path: Path) -> None:
    env = {"EJSRL_PLANT_PORT": str(broker.port)}
    spec = str(EXAMPLES / "paper" / "robualab.ejs.yaml")
    r = _ejsgen("plant", "check", spec, "--timeout", "3", env=env)
    assert r.returncode == 1 and "FAIL the plant sends no state" in r.stdout, r.stdout + r.stderr
    r = _ejsgen("plant", "check", spec, "--timeout", "3", env={"EJSRL_PLANT_PORT": str(free_port())})
    assert r.returncode == 1 and "FAIL no connection to mqtt://127.0.0.1:" in r.stdout, r.stdout + r.stderr
    plant = PlantProc(tmp_path, ["--mqtt", f"127.0.0.1:{broker.port}", "--camera", "off"])
    try:
        r = _ejsgen("plant", "check", spec, "--listen", "1", env=env)
        assert r.returncode == 1 and "FAIL no camera frame from the plant" in r.stdout, r.stdout + r.stderr
        assert "1 check(s) failed" in r.stdout
    finally:
        plant.stop()


def test_check_reports_a_bad_spec_at_file_line_col(tmp_path: Path) -> None:
    text = (EXAMPLES / "paper" / "robualab.ejs.yaml").read_text()
    bad = tmp_path / "lab.ejs.yaml"
    bad.write_text(text.replace("    q_meas: {from: joints, unit: rad}", "    q_mesa: {from: joints, unit: rad}"))
    r = _ejsgen("plant", "check", str(bad))
    line = next(k for k, l in enumerate(bad.read_text().splitlines(), 1) if "q_mesa" in l)
    assert r.returncode == 1 and f"{bad}:{line}:5: error: 'q_mesa' is not a model variable; did you mean 'q_meas'?" in r.stderr, r.stderr
    none = tmp_path / "none.ejs.yaml"
    none.write_text((EXAMPLES / "bouncing_ball.ejs.yaml").read_text())
    r = _ejsgen("plant", "check", str(none))
    first = next(k for k, l in enumerate(none.read_text().splitlines(), 1) if l.strip() and not l.startswith("#"))
    assert r.returncode == 1 and f"{none}:{first}:1: error: this spec has no plant: section" in r.stderr, r.stderr


def test_help_and_a_bad_serve_option() -> None:
    r = _ejsgen("plant", "--help")
    assert r.returncode == 0 and "ejsgen plant serve --mqtt HOST:PORT" in r.stdout and "ejsgen plant check SPEC" in r.stdout
    r = _ejsgen("plant", "serve", "--help")
    assert r.returncode == 0 and "usage: ejsgen plant serve" in r.stdout and "--camera WxH" in r.stdout
    r = _ejsgen("plant", "check", "--help")
    assert r.returncode == 0 and "--listen" in r.stdout
    r = _ejsgen("plant", "serve")
    assert r.returncode == 2 and "give --mqtt HOST:PORT, --opcua HOST:PORT or both" in r.stderr
