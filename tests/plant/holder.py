"""A second app process for the lease tests: it takes the plant, moves joint 1, prints what it holds.

Usage: python holder.py PORT TARGET_DEG; prints 'holding' once it holds the lease and 'sent' after
its command was executed, then heartbeats until killed (or released on stdin 'release')."""

from __future__ import annotations

import math
import sys

from ejsrl.app._plant_link import PlantLink

link = PlantLink("127.0.0.1", int(sys.argv[1]), session="student-a")
assert link.wait_for(lambda l: l.connected and l.state is not None, 30)
link.request_lease()
assert link.wait_for(lambda l: l.holds_lease, 30)
print("holding", flush=True)
target = [math.radians(float(sys.argv[2])), 0, 0, 0, 0]
assert link.send(target) is None
assert link.wait_for(lambda l: (l.state.get("ack") or {}).get("session") == "student-a", 30)
print("sent", flush=True)
for line in sys.stdin:
    if line.strip() == "release":
        link.release_lease()
        link.wait_for(lambda l: not l.holds_lease, 30)
        print("released", flush=True)
