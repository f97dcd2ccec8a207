"""Hostile clients against a served app: what a client sends is checked before viser
stores or broadcasts it (ejsrl.view._guard). Each test drives raw websocket clients that
speak viser's wire format and asserts what users see: the model's value, the values the
other clients are sent, the refusal shown to the sender."""

from __future__ import annotations

import math

import pytest

from testkit.guard_client import CAMERA, Client, gui_update, run_async


def _uuid(served, label: str) -> str:
    return served.view.panel.handles_by_label[label]._impl.uuid


def _run(coro) -> None:
    run_async(coro)


async def _pair(served) -> tuple[Client, Client]:
    """An attacker and a bystander, both past the handshake."""
    port = served.server.get_port()
    evil = await Client.open(port, server=served.server)
    other = await Client.open(port, server=served.server)
    return evil, other


def test_a_client_cannot_remove_or_unhook_a_control_for_everyone(served):
    length = _uuid(served, "Length")

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(gui_update(length, removed=True))
        await evil.send(gui_update(length, update_cb=[]))
        await evil.send(gui_update(length, value=1.5, removed=True))  # a legal value does not carry the rest in
        await evil.send(gui_update(length, label="pwned"))
        await evil.settle()
        assert other.values_of(length) == []  # nothing of it reached the other browser
        assert not [m for m in other.seen("GuiUpdateMessage", uuid=length) if "removed" in m["updates"]]
        assert served.app.model.L == 1.0
        # the slider still works for everyone
        await other.send(gui_update(length, value=1.7))
        await Client.until(lambda: abs(served.app.model.L - 1.7) < 1e-12, "the bystander's value to reach the model")
        await evil.until(lambda: 1.7 in evil.values_of(length), "the attacker's browser to show 1.7")
        await evil.close()
        await other.close()

    _run(scenario())
    assert served.view.panel.handles_by_label["Length"].label == "Length"


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, True, "1.5; import os", [1.0], None])
def test_a_value_that_is_not_a_finite_number_is_refused_and_never_broadcast(served, bad):
    length = _uuid(served, "Length")

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(gui_update(length, value=bad))
        await evil.until(lambda: any("Value refused" in n for n in evil.notifications()), "the refusal to be shown")
        assert any("Length" in n and "not applied" in n for n in evil.notifications())
        # the sender's slider is put back to the value everyone else has
        await evil.until(lambda: evil.values_of(length) == [1.0], "the sender's slider to snap back to 1.0")
        await other.settle()
        assert other.values_of(length) == [] and other.notifications() == []
        await evil.close()
        await other.close()

    _run(scenario())
    assert served.app.model.L == 1.0
    assert served.view.panel.handles_by_label["Length"].value == 1.0


def test_a_huge_number_is_clamped_before_anyone_sees_it(served):
    length = _uuid(served, "Length")

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(gui_update(length, value=1e300))
        await Client.until(lambda: served.app.model.L == 2.0, "L clamped to its maximum 2.0")
        await other.until(lambda: other.values_of(length) == [2.0], "the bystander to be sent 2.0")
        await evil.until(lambda: evil.values_of(length) == [2.0], "the sender to be shown the clamped 2.0")
        assert all(abs(v) <= 2.0 for v in other.values_of(length) + evil.values_of(length))
        await evil.close()
        await other.close()

    _run(scenario())
    # nothing the server broadcast carried the raw value (viser used to, before ejsgen clamped it)
    broadcast = [m.updates["value"] for m in served.messages("GuiUpdateMessage") if m.uuid == length]
    assert broadcast == [2.0]


def test_values_are_not_cast_by_viser_first(served):
    """Before the guard, viser cast ``True`` to 1.0, ``"false"`` to True and 3.7 to 3."""
    count, enabled = _uuid(served, "Count"), _uuid(served, "Enabled")

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(gui_update(enabled, value="false"))  # a non-empty string is truthy in Python
        await evil.until(lambda: len(evil.notifications()) == 1, "the checkbox refusal")
        assert "not true or false" in evil.notifications()[0]
        await evil.send(gui_update(count, value=True))
        await evil.until(lambda: len(evil.notifications()) == 2, "the number field's refusal")
        await evil.send(gui_update(count, value=3.7))  # an int variable: rounded like the UI does, not truncated
        await Client.until(lambda: served.app.model.n == 4, "n == 4")
        await other.until(lambda: other.values_of(count) == [4], "the bystander to see 4")
        await evil.close()
        await other.close()

    _run(scenario())
    assert served.app.model.on is True and isinstance(served.app.model.n, int)


def test_text_and_dropdowns_take_only_what_the_ui_offers(served):
    name, mode = _uuid(served, "Name"), _uuid(served, "Mode")

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(gui_update(mode, value="ludicrous"))
        await evil.send(gui_update(name, value="x" * 15_000))  # under the frame cap, over the text limit
        await evil.until(lambda: len(evil.notifications()) == 2, "both refusals")
        await evil.send(gui_update(mode, value="slow"))
        await Client.until(lambda: served.app.model.mode == "slow", "mode == 'slow'")
        await other.until(lambda: other.values_of(mode) == ["slow"], "the bystander to see 'slow'")
        assert other.values_of(name) == []
        await evil.close()
        await other.close()

    _run(scenario())
    assert served.app.model.name == "lab"


def test_a_client_that_skipped_the_handshake_changes_nothing(served):
    """viser broadcast the values of a client that never sent its camera (so was never
    registered), without running ejsgen's callback: the other browsers showed a value the
    model did not have."""
    length = _uuid(served, "Length")

    async def scenario():
        port = served.server.get_port()
        other = await Client.open(port, server=served.server)
        sneaky = await Client.open(port, camera=False)
        await sneaky.send(gui_update(length, value=1.9))
        await sneaky.settle()
        assert other.values_of(length) == []
        await sneaky.close()
        await other.close()

    _run(scenario())
    assert served.app.model.L == 1.0
    assert served.view.panel.handles_by_label["Length"].value == 1.0


def test_messages_the_ui_never_sends_are_dropped_and_the_connection_keeps_working(served):
    length = _uuid(served, "Length")
    junk = [
        {"type": "ShareUrlRequest"},  # would open a public tunnel to the lab
        {"type": "FileTransferStartUpload", "source_component_uuid": length, "transfer_uuid": "t", "filename": "a",
         "mime_type": "x", "part_count": 1, "size_bytes": 10},
        {"type": "GuiFormDirtyMessage", "uuid": length},
        {"type": "NoSuchMessage"},
        {"no": "type"},
        {"type": "ViewerCameraMessage", "wxyz": [math.nan, 0, 0, 0]},
        {"type": "GuiUpdateMessage", "uuid": "not-a-control", "updates": {"value": 1}},
        b"\xc1 not msgpack",
        b"\x91" * 60_000 + b"\x00",  # arrays nested 60,000 deep: the decoder's recursion limit
        "a text frame",
    ]

    async def scenario():
        evil, other = await _pair(served)
        for message in junk:
            await evil.send(message)
        await evil.send(gui_update(length, value=0.5))
        await Client.until(lambda: served.app.model.L == 0.5, "the same connection's next update to work")
        assert evil.closed is None
        # and the UI offers no share button (a public tunnel to the lab)
        themes = evil.seen("ThemeConfigurationMessage")
        assert themes and themes[-1]["show_share_button"] is False
        await evil.close()
        await other.close()

    _run(scenario())
    guard = __import__("ejsrl.view._guard", fromlist=["guard_of"]).guard_of(served.server)
    assert guard.dropped.get("kind ShareUrlRequest") == 1


def test_a_gizmo_drag_with_a_broken_pose_is_dropped(served):
    handle = "/ejs/handle"

    def drag(position, wxyz=(1.0, 0.0, 0.0, 0.0)):
        return {"type": "TransformControlsUpdateMessage", "name": handle, "wxyz": list(wxyz),
                "position": list(position), "owner": ""}

    async def scenario():
        evil, other = await _pair(served)
        await evil.send(drag([math.nan, 0.0, 0.0]))
        await evil.send(drag([1e300, 0.0, 0.0]))
        await evil.send(drag([0.5, 0.0, 0.0], wxyz=(0.0, 0.0, 0.0, 0.0)))
        await evil.settle()
        assert served.app.model.k == 1.0
        await evil.send(drag([0.5, 0.0, 0.0]))  # the gizmo's setter: k = x + 2
        await Client.until(lambda: abs(served.app.model.k - 2.5) < 1e-12, "k == 2.5 after a real drag")
        await evil.close()
        await other.close()

    _run(scenario())


def test_the_camera_message_is_rebuilt_from_its_known_fields(served):
    async def scenario():
        port = served.server.get_port()
        client = await Client.open(port, camera=False)
        await client.send({**CAMERA, "surprise": 1})  # viser's decoder raised on an unknown field
        await Client.until(lambda: len(served.server.get_clients()) == 1, "the client to be registered")
        await client.close()

    _run(scenario())
