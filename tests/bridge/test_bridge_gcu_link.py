"""How the bridge reads the GCU link (gcu_async.bridge.gcu_link; docs/mavlink-bridge.md, "The
bridge contract", BG9, and "Robustness"): when the GCU is ready for a command, and what the
bridge does when the client's transport gave up or the link restarted. No I/O."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import Any

import pytest

from gcu_async.bridge import MavlinkBridge, gcu_link
from gcu_async.client.client import ClientState
from gcu_async.protocol.enums import Mode
from gcu_async.session import SessionConfig
from gcu_async.transport.base import LinkEvent, LinkEventKind


@dataclass
class Health:
    up: bool = True
    last_reply_age: float | None = 0.05


@dataclass
class Session:
    config: SessionConfig = field(default_factory=SessionConfig)


@dataclass
class FakeClient:
    """What the bridge reads of a client, and its open/close calls."""

    state: Any = ClientState.OPEN
    link: Health = field(default_factory=Health)
    session: Session = field(default_factory=Session)
    calls: list[str] = field(default_factory=list)

    async def close(self) -> None:
        self.calls.append("close")
        self.state = ClientState.CLOSED

    async def open(self) -> None:
        self.calls.append("open")
        self.state = ClientState.OPEN


@pytest.mark.parametrize(("client", "ready"), [
    (FakeClient(), True),
    (FakeClient(link=Health(last_reply_age=0.2)), True),
    (FakeClient(link=Health(last_reply_age=0.21)), False),  # silent: values would go invalid
    (FakeClient(link=Health(last_reply_age=None)), False),  # no reply yet
    (FakeClient(link=Health(up=False)), False),
    (FakeClient(state=ClientState.OPENING), False),
    (FakeClient(state=ClientState.CLOSED), False),
])  # fmt: skip
def test_ready_means_open_up_and_a_reply_within_control_silence(client: FakeClient,
                                                                ready: bool) -> None:  # fmt: skip
    assert gcu_link.ready(client) is ready  # type: ignore[arg-type]


def bridge_for(client: FakeClient) -> MavlinkBridge:
    return MavlinkBridge(client, ["udpout:127.0.0.1:9"])  # type: ignore[arg-type]


async def test_a_transport_that_gave_up_is_closed_and_opened_again_once() -> None:
    client = FakeClient(state=ClientState.FAILED)
    bridge = bridge_for(client)
    assert gcu_link.failed(client)  # type: ignore[arg-type]
    bridge._on_gcu_event(LinkEvent(LinkEventKind.GAVE_UP))
    bridge._on_gcu_event(LinkEvent(LinkEventKind.GAVE_UP))
    bridge._start_reopen()  # (what the heartbeat step does on seeing FAILED)
    for _ in range(5):
        await asyncio.sleep(0)
    assert client.calls == ["close", "open"]
    assert client.state is ClientState.OPEN and not bridge._reopening


async def test_after_a_restart_the_bridge_forgets_the_mode_it_set() -> None:
    bridge = bridge_for(FakeClient())
    bridge.executor.bridge_mode = Mode.EULER_CONTROL
    bridge.executor.tracking_mode, bridge.executor.tracking_box = 2, (0.4, 0.4, 0.6, 0.6)
    bridge._on_gcu_event(LinkEvent(LinkEventKind.RESTARTED))
    assert bridge.executor.bridge_mode is None
    assert (bridge.executor.tracking_mode, bridge.executor.tracking_box) == (0, None)
