"""Real servers for the plant tests (tests/plant), each on a free 127.0.0.1 port: Debian's
mosquitto with a temporary config, and the reference plant as its own process.

Kept here rather than in tests/plant/conftest.py: test modules import these names, and
``from conftest import ...`` finds whichever folder's conftest a worker imported first."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

MOSQUITTO = shutil.which("mosquitto") or "/usr/sbin/mosquitto"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_port(port: int, timeout: float = 20.0) -> None:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            socket.create_connection(("127.0.0.1", port), 0.5).close()
            return
        except OSError:
            time.sleep(0.05)
    raise TimeoutError(f"nothing listens on 127.0.0.1:{port}")


@dataclass
class Broker:
    """A mosquitto broker on 127.0.0.1:``port``, restartable on the same port."""

    dir: Path
    port: int
    passwd: dict[str, str] = field(default_factory=dict)
    proc: subprocess.Popen | None = None
    #: TCP_NODELAY toward the clients, as specs/language.md advises (else Nagle's algorithm holds a
    #: small message back until the client acknowledges the one before: up to 40 ms on Linux)
    nodelay: bool = True

    def start(self) -> None:
        conf = self.dir / "mosquitto.conf"
        lines = [f"listener {self.port} 127.0.0.1", "persistence false", "log_dest stderr"]
        if self.nodelay:
            lines.append("set_tcp_nodelay true")
        if os.geteuid() == 0:
            lines.append("user root")  # else it drops to user mosquitto, who cannot read this test's folder
        if self.passwd:
            pw = self.dir / "passwd"
            pw.unlink(missing_ok=True)
            for user, password in self.passwd.items():
                flag = ["-c"] if not pw.exists() else []
                subprocess.run(["mosquitto_passwd", "-b", *flag, str(pw), user, password], check=True)
            lines += ["allow_anonymous false", f"password_file {pw}"]
        else:
            lines.append("allow_anonymous true")
        conf.write_text("\n".join(lines) + "\n")
        self.log = open(self.dir / "mosquitto.log", "ab")
        self.proc = subprocess.Popen([MOSQUITTO, "-c", str(conf)], stdout=self.log, stderr=self.log)
        wait_port(self.port)

    def kill(self) -> None:
        if self.proc and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
            self.proc.wait(10)



class PlantProc:
    """``python -m ejsrl.plant`` as a child process; ``out`` and ``err`` are its logs."""

    def __init__(self, tmp: Path, args: list[str], env: dict[str, str] | None = None) -> None:
        self.out_path, self.err_path = tmp / "plant.out", tmp / "plant.err"
        self.proc = subprocess.Popen([sys.executable, "-m", "ejsrl.plant", *args],
                                     stdout=open(self.out_path, "wb"), stderr=open(self.err_path, "wb"),
                                     env={**os.environ, **(env or {})})
        end = time.monotonic() + 60
        while b"ready" not in self.out_path.read_bytes():
            if self.proc.poll() is not None or time.monotonic() > end:
                raise RuntimeError(f"the plant did not start: {self.err_path.read_text()}")
            time.sleep(0.05)

    def logs(self) -> str:
        return self.out_path.read_text() + self.err_path.read_text()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


class ConnectedLinks:
    """``with ConnectedLinks(new) as make``: ``make(**kw)`` calls ``new(**kw)`` (a plant link over
    MQTT or OPC UA) and waits until it is connected with the plant's state; every link made is
    closed on leaving."""

    def __init__(self, new: Callable[..., Any]) -> None:
        self.new = new
        self.links: list[Any] = []

    def __enter__(self) -> Callable[..., Any]:
        return self.make

    def make(self, **kw: Any) -> Any:
        link = self.new(**kw)
        self.links.append(link)
        assert link.wait_for(lambda l: l.connected and l.state is not None, 30), link.note
        return link

    def __exit__(self, *exc: object) -> None:
        for link in self.links:
            link.close()
