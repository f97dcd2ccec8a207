"""One wake of viser's event loop for many sessions' frames (ejsrl.app._wake, issue #30).

With viser's own buffers and a real asyncio loop in its own thread, as a served class has
them: every client's frame reaches its window (nothing is lost or reordered), frames that
end while the loop is busy share one wake (a class's 80 sessions were 2,400 self-pipe
writes and GIL hand-overs a second), and a lone frame still wakes the loop at once.
"""

from __future__ import annotations

import asyncio
import threading
import time

from viser import _messages
from viser.infra._async_message_buffer import AsyncMessageBuffer

from ejsrl.app._wake import BatchedWake


class _Loop:
    """An event loop running in its own thread (viser's is one)."""

    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self.thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self.thread.start()

    def run(self, coro, timeout: float = 10.0):
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def stop(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self.thread.join(5)


def _frame(buffer: AsyncMessageBuffer, k: int) -> None:
    """One session's frame: a position and a readout text, in one atomic block."""
    buffer.atomic_start()
    buffer.push(_messages.SetPositionMessage(f"/bob{k}", (float(k), 0.0, 0.0)))
    buffer.push(_messages.SetPositionMessage(f"/arm{k}", (0.0, float(k), 0.0)))
    buffer.atomic_end()


async def _first_window(buffer: AsyncMessageBuffer, client_id: int) -> list:
    gen = buffer.window_generator(client_id)
    try:
        return list(await asyncio.wait_for(gen.__anext__(), 5.0))
    finally:
        await gen.aclose()


def _until_waiting(buffers: list[AsyncMessageBuffer]) -> None:
    """Until every buffer's producer (its window generator) runs and waits for messages."""
    deadline = time.monotonic() + 10
    while not all(len(b.generator_cursors) == 1 for b in buffers):
        assert time.monotonic() < deadline, "the producers did not start"
        time.sleep(0.01)


def test_frames_ending_while_the_loop_is_busy_share_one_wake_and_all_arrive():
    runner = _Loop()
    try:
        wake = BatchedWake(runner.loop)
        buffers = [AsyncMessageBuffer(runner.loop, persistent_messages=False) for _ in range(10)]
        assert all(wake.install(b) for b in buffers)
        # every client's producer waits for its messages, as viser's do
        waiting = [asyncio.run_coroutine_threadsafe(_first_window(b, i), runner.loop) for i, b in enumerate(buffers)]
        _until_waiting(buffers)
        busy, release = threading.Event(), threading.Event()
        runner.loop.call_soon_threadsafe(lambda: (busy.set(), release.wait(5)))  # the loop waits for the GIL
        assert busy.wait(5)
        for k, b in enumerate(buffers):  # ten sessions' frames end meanwhile
            _frame(b, k)
        assert (wake.ends, wake.wakes) == (10, 1)
        release.set()
        windows = [w.result(5) for w in waiting]
        for k, window in enumerate(windows):  # each client gets its own frame, whole and in order
            assert [(m.name, m.position) for m in window] == [(f"/bob{k}", (float(k), 0.0, 0.0)), (f"/arm{k}", (0.0, float(k), 0.0))]
    finally:
        runner.stop()


def test_a_lone_frame_wakes_the_loop_at_once():
    runner = _Loop()
    try:
        wake = BatchedWake(runner.loop)
        buffer = AsyncMessageBuffer(runner.loop, persistent_messages=False)
        assert wake.install(buffer)
        for k in range(3):
            waiting = asyncio.run_coroutine_threadsafe(_first_window(buffer, 0), runner.loop)
            _until_waiting([buffer])
            t = time.monotonic()
            _frame(buffer, k)
            window = waiting.result(5)
            assert time.monotonic() - t < 1.0  # not left for a later frame's wake
            assert [m.name for m in window] == [f"/bob{k}", f"/arm{k}"]
        assert wake.wakes == wake.ends == 3
    finally:
        runner.stop()


def test_a_buffer_of_another_loop_is_left_as_viser_made_it():
    runner, other = _Loop(), _Loop()
    try:
        wake = BatchedWake(runner.loop)
        buffer = AsyncMessageBuffer(other.loop, persistent_messages=False)
        assert not wake.install(buffer)
        assert "atomic_end" not in vars(buffer)
    finally:
        runner.stop()
        other.stop()
