"""Over a real UDP socket on 127.0.0.1: a raw host sending CRC-valid packets the document does
not expect (time zone +15, a camera mask of 0, a photo with two parameter bytes, version 3) at
50 Hz sees a reply to every one — failure status where the command cannot run (the photo
with mask 0 runs: docs/protocol-notes.md §14) — and the
simulator still takes the aircraft data each packet carries (docs/client.md, "Liberal receive,
strict send")."""

from __future__ import annotations

import asyncio

import pytest

from gcu_async.protocol import HOST_HEADER, ExecutionStatus, decode_gcu_packet
from gcu_async.sim import GcuSimulator
from helpers.protocol.strategies import seal
from helpers.sim.support import UdpPeer, host_bytes

ODD = [  # (opcode, parameter bytes, version): each CRC-valid, each unexpected
    (0x08, b"\x0f", 2),  # time zone +15
    (0x20, b"\x00", 2),  # photo with camera mask 0: executed all the same (protocol-notes §14)
    (0x00, b"", 3),  # a null command in version 3
    (0x2A, b"\x02\x0b", 1),  # palette 11
    (0x21, b"\x01\x01", 2),  # record with two parameter bytes
]


def odd_packet(i: int) -> tuple[bytes, float]:
    """Packet ``i`` of the run and the aircraft yaw it carries (INS valid)."""
    opcode, params, version = ODD[i % len(ODD)]
    yaw = float(i % 360)
    valid = host_bytes(attitude=(1.5, -2.0, yaw))
    return seal(HOST_HEADER, valid[5:69] + bytes([opcode]) + params, version), yaw


async def test_a_host_sending_unexpected_packets_at_50_hz_gets_replies() -> None:
    peer = await UdpPeer.open()
    sim = GcuSimulator()
    try:
        async with sim.serve_udp(port=0) as server:
            count = 50
            loop = asyncio.get_running_loop()
            start = loop.time()
            last_yaw = 0.0
            for i in range(count):  # on a 50 Hz schedule, not waiting for replies
                await asyncio.sleep(max(0.0, start + i * 0.02 - loop.time()))
                packet, last_yaw = odd_packet(i)
                peer.send(packet, server.address)
            replies = [decode_gcu_packet((await peer.receive(timeout=2.0))[0])
                       for _ in range(count)]  # fmt: skip
            aircraft = sim.model.state.aircraft
            assert aircraft.packets == count  # the aircraft data of every packet was taken
            assert aircraft.ins_valid_packets == count
            assert tuple(aircraft.attitude) == pytest.approx((1.5, -2.0, last_yaw))
    finally:
        await peer.close()
    assert len(replies) == count
    for i, reply in enumerate(replies):
        opcode = ODD[i % len(ODD)][0]
        assert reply.feedback.opcode == opcode
        if opcode == 0x20:  # tolerated: docs/protocol-notes.md §14
            assert reply.feedback.result is ExecutionStatus.SUCCESS
        elif opcode != 0x00:
            assert reply.feedback.result is ExecutionStatus.FAILED
    stats = sim.model.stats
    assert stats.answered == count
    assert stats.anomalous == count // len(ODD) * 4  # every packet but the version-3 null
    assert stats.tolerated == count // len(ODD)
    assert stats.other_versions == count // len(ODD)
    assert stats.malformed == 0
