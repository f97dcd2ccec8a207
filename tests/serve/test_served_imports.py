"""A served class loads OpenCV only for a lab that uses vision (issue #30).

The class keeps SUSAN to one thread a call (its sessions already share the cores); setting
that imported SUSAN, and with it OpenCV (0.16 s, 80 ms of it cv2's own import), into every
served lab. Each lab is served here as a teacher serves it, in a fresh Python process, and
its modules are read once it serves.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

_PROBE = """
import json, os, sys
from ejsrl.app import load_app
app = load_app(sys.argv[1])
server = app.serve("127.0.0.1", 0, block=False, per_client=True)
loaded = {m: m in sys.modules for m in ("cv2", "ejsrl.vision._susan")}
from ejsrl.vision._susan import susan_threads
print(json.dumps({"loaded": loaded, "susan_threads": susan_threads(), "places": app.classroom.max_sessions}))
app.stop()
server.stop()
"""


def _serve_and_read(app_dir: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "EJSRL_SUSAN_THREADS"}
    out = subprocess.run([sys.executable, "-P", "-c", _PROBE, str(app_dir)], capture_output=True, text=True,
                         timeout=300, env=env, cwd=app_dir)
    assert out.returncode == 0, out.stderr[-3000:]
    return json.loads(next(line for line in out.stdout.splitlines() if line.startswith('{"loaded"')))


def test_a_lab_without_vision_is_served_without_opencv(built):
    r = _serve_and_read(built("pendulum"))
    assert r["loaded"] == {"cv2": False, "ejsrl.vision._susan": False}
    assert r["susan_threads"] == 1  # were SUSAN loaded later (a student's code), it keeps to one thread
    assert r["places"] >= 2


def test_a_served_vision_lab_keeps_susan_to_one_thread(built):
    r = _serve_and_read(built("paper/visual_servoing_eih"))
    assert r["susan_threads"] == 1
