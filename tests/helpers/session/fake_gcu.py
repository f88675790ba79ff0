"""A scripted GCU on an in-memory link for session unit tests: records every host packet
and answers with a feedback chosen by a test-supplied function."""

from __future__ import annotations

from collections.abc import Callable

from gcu_async.protocol import (
    Deframer,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostPacket,
    Mode,
    command_code,
    decode_host_packet,
)
from gcu_async.session.control import REPORTED
from gcu_async.transport.memory import MemoryTransport


def succeed(packet: HostPacket) -> Feedback | None:
    """Success for every command (no status for the null command)."""
    op = command_code(packet.command)
    return Feedback(op, None if op == 0 else 0)


class FakeGcu:
    """``answer(packet)`` returns the feedback to send, or ``None`` to stay silent. A mode
    command answered with success switches the mode the main frame reports."""

    def __init__(self, answer: Callable[[HostPacket], Feedback | None] = succeed) -> None:
        self.client_end, self._end = MemoryTransport.pair(("client", "fake-gcu"))
        self._end.set_handlers(self._received)
        self._deframer = Deframer.for_host_packets()
        self.answer = answer
        self.packets: list[HostPacket] = []
        self.sub = GcuSubFrame.build(pod_model=45, camera1_zoom=1.0)
        self.mode = Mode.POINTING_FOLLOW

    async def start(self) -> None:
        await self._end.open()

    async def stop(self) -> None:
        await self._end.close()

    def _received(self, data: bytes) -> None:
        for raw in self._deframer.feed(data):
            packet = decode_host_packet(raw)
            self.packets.append(packet)
            feedback = self.answer(packet)
            opcode = command_code(packet.command)
            if feedback is not None and feedback.status == 0 and opcode in REPORTED:
                self.mode = REPORTED[opcode]
            if feedback is not None and self._end.connected:
                main = GcuMainFrame.build(mode=self.mode)
                self._end.send(GcuPacket(main, self.sub, feedback).encode())
