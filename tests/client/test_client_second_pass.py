"""Issue 25's API items, as a new user meets them: ``ClientState`` from ``gcu_async``,
``LinkHealth.as_dict()``, what a reply to the null command carries as feedback, and the
log line of an OS error on the link in plain words — against the simulator over UDP."""

from __future__ import annotations

import asyncio
import json
import logging
import socket
from dataclasses import fields
from typing import get_type_hints

import pytest

import gcu_async
from gcu_async import ClientState, GcuClient, LinkHealth, TelemetrySample, connect
from gcu_async.protocol.enums import ExecutionStatus, Opcode
from gcu_async.session.health import LinkHealthDict


def test_client_state_is_the_clients() -> None:
    assert gcu_async.ClientState is gcu_async.client.ClientState
    gcu = connect("udp://127.0.0.1:4000", local_port=0)
    assert gcu.state is ClientState.CLOSED


async def test_link_health_as_dict_is_every_field_and_json(gcu_client: GcuClient) -> None:
    health = gcu_client.link
    data = health.as_dict()
    assert list(data) == [f.name for f in fields(LinkHealth)]
    assert data == {f.name: getattr(health, f.name) for f in fields(LinkHealth)}
    assert data["up"] is True and data["packets_received"] >= 1
    assert json.loads(json.dumps(data)) == data
    hints = get_type_hints(LinkHealthDict)  # the TypedDict is the dataclass's fields
    assert hints == get_type_hints(LinkHealth)


async def test_a_reply_to_the_null_command_carries_a_feedback_of_opcode_0(
    gcu_client: GcuClient,
) -> None:
    """Nothing in flight: the GCU answers the heartbeat's null command, and the sample's
    feedback is a ``Feedback`` (never ``None``) with opcode 0 and no status, so
    ``sample.feedback.opcode`` and ``as_dict()`` always work."""
    samples = gcu_client.telemetry()
    sample: TelemetrySample = await samples.__anext__()
    await samples.aclose()
    assert sample.feedback is not None
    feedback = sample.feedback
    assert (feedback.opcode, feedback.status, feedback.result) == (Opcode.NULL, None,
                                                                   ExecutionStatus.NONE)
    assert feedback.as_dict() == {"command": "NULL", "opcode": 0, "status": "NONE",
                                  "status_raw": None, "failed_cameras": 0}  # fmt: skip


async def test_an_os_error_on_the_link_is_logged_in_plain_words(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Nothing listens at the GCU's port: the OS reports it (ICMP port unreachable) and the
    client says what happens next in plain words."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]  # free once closed: nothing listens there
    caplog.set_level(logging.WARNING, logger="gcu_async.client")
    async with connect(f"udp://127.0.0.1:{port}", local_port=0, wait=False) as gcu:
        for _ in range(200):  # bounded: the first heartbeat's ICMP error comes at once
            if any("ICMP" in r.getMessage() for r in caplog.records):
                break
            await asyncio.sleep(0.01)
        assert gcu.state is ClientState.OPENING
    [line] = [r.getMessage() for r in caplog.records if "ICMP" in r.getMessage()]
    assert line.endswith("(the client keeps sending; the link is up once the GCU answers)")
    assert "link health" not in line
