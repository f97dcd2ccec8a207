"""The plant's OPC UA side (asyncua): the same plant as an OPC UA server, for industrial cells.

Address space under the object ``Plant`` in namespace ``urn:ejsrl:plant``: variables
``Measured`` (Double[5], rad), ``Gripper`` (Double), ``Status`` (String), ``State`` (String: the
JSON of :meth:`Plant.state`, for clients that want every field) updated ``rate`` times a second,
``Video`` (ByteString: the camera's newest frame message, see :mod:`._video`) and ``VideoSeq``
(Int64: its number, so a client reads the frame only when it changed);
methods ``Lease(session, op) -> String``, ``Heartbeat(session)``,
``Command(session, epoch, seq, t, q[5], gripper) -> String`` (empty when executed, else why it
was refused) and ``EStop(session, on)``.
"""

from __future__ import annotations

import asyncio
import json
import threading
from typing import TYPE_CHECKING, Any

from ._core import Plant

if TYPE_CHECKING:
    from ._camera import PlantCamera

__all__ = ["OpcUaPlant", "NAMESPACE"]

NAMESPACE = "urn:ejsrl:plant"


def import_asyncua() -> Any:
    try:
        import asyncua
    except ImportError as e:  # pragma: no cover
        raise ImportError("the OPC UA transport needs asyncua: python3 -m pip install 'ejsgen[plant]'") from e
    return asyncua


class OpcUaPlant:
    """Serve ``plant`` at ``opc.tcp://host:port/ejsrl/plant/`` from a thread of its own."""

    def __init__(self, plant: Plant, host: str, port: int, *, rate: float = 50.0, camera: PlantCamera | None = None) -> None:
        self.plant, self.host, self.port, self.rate = plant, host, port, rate
        self.camera = camera
        self._frame: bytes | None = None       # the camera's newest frame, not yet written
        if camera is not None:
            camera.sinks.append(self._take_frame)
        self.endpoint = f"opc.tcp://{host}:{port}/ejsrl/plant/"
        self.ready = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self.error: BaseException | None = None

    def start(self) -> None:
        threading.Thread(target=self._thread, name="ejsrl-plant-opcua", daemon=True).start()

    def _take_frame(self, frame: bytes) -> None:
        self._frame = frame                    # the server's loop writes the newest one; others are dropped

    def stop(self) -> None:
        if self._loop and self._stop:
            self._loop.call_soon_threadsafe(self._stop.set)

    def _thread(self) -> None:
        self._loop = asyncio.new_event_loop()
        try:
            self._loop.run_until_complete(self._serve())
        except BaseException as e:  # reported by the CLI
            self.error = e
            self.ready.set()

    async def _serve(self) -> None:
        asyncua = import_asyncua()
        ua = asyncua.ua
        uamethod = asyncua.uamethod
        plant = self.plant
        server = asyncua.Server()
        await server.init()
        server.set_endpoint(self.endpoint)
        server.set_server_name("ejsrl reference plant")
        server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
        idx = await server.register_namespace(NAMESPACE)
        obj = await server.nodes.objects.add_object(idx, "Plant")
        measured = await obj.add_variable(idx, "Measured", [0.0] * 5, varianttype=ua.VariantType.Double)
        gripper = await obj.add_variable(idx, "Gripper", 0.0)
        status = await obj.add_variable(idx, "Status", "idle")
        state = await obj.add_variable(idx, "State", "{}")
        video = await obj.add_variable(idx, "Video", b"", varianttype=ua.VariantType.ByteString)
        video_seq = await obj.add_variable(idx, "VideoSeq", 0, varianttype=ua.VariantType.Int64)
        seq = 0

        @uamethod
        def lease(parent: Any, session: str, op: str) -> str:
            return json.dumps(plant.lease(session, op)) if op in ("request", "release") else "op is request or release"

        @uamethod
        def heartbeat(parent: Any, session: str) -> None:
            plant.heartbeat(session)

        @uamethod
        def command(parent: Any, session: str, epoch: int, seq: int, t: float, q: list[float], grip: float) -> str:
            return plant.command({"session": session, "epoch": epoch, "seq": seq, "t": t, "q": list(q), "gripper": grip}) or ""

        @uamethod
        def estop(parent: Any, session: str, on: bool) -> None:
            plant.estop(session, bool(on))

        S, I, D, B = ua.VariantType.String, ua.VariantType.Int64, ua.VariantType.Double, ua.VariantType.Boolean
        await obj.add_method(idx, "Lease", lease, [S, S], [S])
        await obj.add_method(idx, "Heartbeat", heartbeat, [S], [])
        await obj.add_method(idx, "Command", command, [S, I, I, D, D, D], [S])
        await obj.add_method(idx, "EStop", estop, [S, B], [])
        self._stop = asyncio.Event()
        async with server:
            self.ready.set()
            while not self._stop.is_set():
                st = plant.state()
                await measured.write_value(st["q"], ua.VariantType.Double)
                await gripper.write_value(float(st["gripper"]))
                await status.write_value(st["status"])
                await state.write_value(json.dumps(st))
                frame, self._frame = self._frame, None
                if frame is not None:
                    seq += 1
                    await video.write_value(frame, ua.VariantType.ByteString)
                    await video_seq.write_value(seq, ua.VariantType.Int64)
                try:
                    await asyncio.wait_for(self._stop.wait(), 1.0 / self.rate)
                except asyncio.TimeoutError:
                    pass
