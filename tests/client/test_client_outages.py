"""Outages of any length, GCU restarts, starting before the GCU, giving up (docs/client.md,
"Lifecycle" and "GCU restarts"): the whole client — driver, session, waits — against the
simulator in memory, in virtual time (tests/helpers/transport/vclock.py), so an hour-long
outage takes a second. tests/client/test_client_outage_matrix.py shows the same over real
sockets, a pty and a simulator process.

An outage is either silent (the GCU stops answering: UDP's case) or dropped (the link itself
goes, as a TCP connection or a serial device does, and comes back); a restart is a dropped
link that comes back to a fresh simulator model (its state at power-on)."""

from __future__ import annotations

import asyncio
import logging
import math
from collections import Counter
from typing import Any

import pytest

from gcu_async import CommandLinkLost, GcuClient, LinkLost, Mode, Outcome
from gcu_async.client import ClientState
from gcu_async.protocol import Opcode
from gcu_async.sim import GcuSimulator, SimulatorModel
from gcu_async.transport import LinkEvent, LinkEventKind, MemoryTransport, Transport
from helpers.scale import FULL
from helpers.transport.vclock import LoopClock, run

K = LinkEventKind
OUTAGES = (2.0, 30.0, 120.0, 3600.0) if FULL else (2.0, 30.0, 120.0)
"""Outage lengths (an hour of heartbeats is 5 s of CPU: full size only)."""
POD = "D-90Pro(TA)"


class Gate(Transport):
    """The client's end of the in-memory link, with the failures of a real transport: it
    refuses to open until ``opens_at`` (a TCP port nobody listens on, a serial adapter not
    plugged in), and :meth:`give_up` plays a transport whose reconnection ran out."""

    def __init__(self, inner: MemoryTransport, opens_at: float = 0.0) -> None:
        super().__init__()
        self.inner = inner
        self.opens_at = opens_at
        self.refused = 0

    @property
    def url(self) -> str:
        return "gate://gcu"

    @property
    def connected(self) -> bool:
        return self.inner.connected

    def set_handlers(self, on_data: Any, on_event: Any = None) -> None:
        super().set_handlers(on_data, on_event)
        self.inner.set_handlers(on_data, on_event)

    async def open(self) -> None:
        if asyncio.get_running_loop().time() < self.opens_at:
            self.refused += 1
            raise LinkLost(f"{self.url}: cannot connect: refused")
        await self.inner.open()

    def send(self, data: bytes) -> None:
        self.inner.send(data)

    async def close(self) -> None:
        await self.inner.close()

    async def give_up(self) -> None:
        """The link drops and the transport will not restore it."""
        self.inner._open = False
        self._on_event(LinkEvent(K.LOST, f"{self.url}: connection lost"))
        self._on_event(LinkEvent(K.GAVE_UP, f"giving up after 3 reconnect attempts ({self.url})"))


class Rig:
    """The simulator (in memory, on the loop's clock) and a client of it; every GCU model it
    ever ran (one per restart) and every link event with its time."""

    def __init__(self, *, opens_at: float | None = None, **options: Any) -> None:
        self.loop = asyncio.get_running_loop()
        self.models = [SimulatorModel(POD, clock=LoopClock(), record_executions=True)]
        self.sim = GcuSimulator(self.models[0])
        self.server = self.sim.serve_memory()
        transport: Transport = self.server.transport
        if opens_at is not None:
            transport = self.gate = Gate(self.server.transport, opens_at)
        self.gcu = GcuClient(transport, clock=self.loop.time, **options)
        self.events: list[tuple[float, LinkEvent]] = []
        self.gcu.on_link_change(lambda event: self.events.append((self.loop.time(), event)))

    def kinds(self) -> list[LinkEventKind]:
        return [event.kind for _, event in self.events]

    def executed(self) -> Counter[int]:
        """Executions of every model so far, by opcode."""
        return sum((model.executions for model in self.models), Counter())

    async def drop(self, seconds: float, *, restart: str | None = None) -> float:
        """The link drops for ``seconds`` (with ``restart``: the GCU comes back as a fresh
        model of that pod); returns when it came back."""
        await self.server.close()
        await asyncio.sleep(seconds)
        if restart is not None:
            self.models.append(SimulatorModel(restart, clock=LoopClock(), record_executions=True))
            self.sim.model = self.models[-1]
        await self.server.open()
        return self.loop.time()

    async def outage(self, kind: str, seconds: float) -> float:
        if kind == "dropped":
            return await self.drop(seconds)
        self.sim.silence(seconds)
        back = self.loop.time() + seconds
        await asyncio.sleep(seconds)
        return back


async def put_out_of_defaults(gcu: GcuClient) -> None:
    """Euler control at pitch -30, yaw 90; zoom 5x; ranging on."""
    await gcu.enter_euler_control(roll=0.0, pitch=-30.0, yaw=90.0)
    await gcu.reach_zoom(5.0, timeout=20.0)
    await gcu.set_ranging(True)
    await gcu.wait_attitude(pitch=-30.0, yaw=90.0, timeout=20.0)
    await asyncio.sleep(2.0)  # settled: no change under way (gcu_async.session.restart)


# -- outages -----------------------------------------------------------------------------
@pytest.mark.parametrize(("kind", "seconds"), [
    *(("silent", s) for s in OUTAGES if s < 3600), *(("dropped", s) for s in OUTAGES)])
def test_an_outage_of_any_length_ends_by_itself(kind: str, seconds: float) -> None:
    async def main() -> None:
        rig = Rig()
        async with rig.server, rig.gcu as gcu:
            await put_out_of_defaults(gcu)
            started = rig.loop.time()
            outage = asyncio.ensure_future(rig.outage(kind, seconds))
            await gcu.wait_link(False, timeout=5.0)
            with pytest.raises(CommandLinkLost) as info:
                await gcu.take_photo()
            assert info.value.outcome is Outcome.NOT_SENT
            assert gcu.state is ClientState.OPEN and not gcu.link.up
            back = await outage
            await gcu.wait_link(True, timeout=10.0)
            assert rig.loop.time() - back < 0.1  # the first heartbeat after it is answered
            assert back - started >= seconds - 1e-6
            assert gcu.state is ClientState.OPEN
            await gcu.take_photo()
            assert gcu.link.lost_count == gcu.link.restored_count == 1
        assert rig.kinds() == [K.UP, K.LOST, K.RESTORED]  # and no RESTARTED
        assert rig.executed() == Counter({Opcode.EULER_CONTROL: 1, Opcode.ZOOM_TO: 1,
                                          Opcode.RANGING: 1, Opcode.TAKE_PHOTO: 1})  # fmt: skip

    run(main(), timeout=seconds + 600.0)


# -- restarts ----------------------------------------------------------------------------
@pytest.mark.parametrize("restore", [False, True])
def test_a_restart_is_reported_and_restored_on_request(restore: bool) -> None:
    async def main() -> None:
        rig = Rig(restore=restore)
        async with rig.server, rig.gcu as gcu:
            await put_out_of_defaults(gcu)
            assert gcu.control_valid
            before = rig.executed()
            await rig.drop(45.0, restart=POD)
            await gcu.wait_link(True, timeout=10.0)
            if restore:
                await gcu.wait_zoom(5.0, timeout=20.0)
                await gcu.wait_attitude(pitch=-30.0, yaw=90.0, timeout=20.0)
                status = gcu.status
                assert status is not None and status.mode is Mode.EULER_CONTROL
                assert gcu.control_valid
            else:
                await asyncio.sleep(20.0)
                info = gcu.info
                assert info is not None and info.camera1_zoom == 1.0
                assert not gcu.control_valid  # the values were for a mode the GCU left
            assert gcu.link.restarted_count == 1
        assert rig.kinds() == [K.UP, K.LOST, K.RESTORED, K.RESTARTED]
        detail = rig.events[-1][1].detail
        assert detail.startswith("the GCU restarted: mode EULER_CONTROL -> POINTING_FOLLOW, "
                                 "zoom 5x -> 1x, ranging on -> off")  # fmt: skip
        assert detail.endswith("; restoring mode EULER_CONTROL and zoom 5x") is restore
        # the first GCU executed each command once; the restarted one only the restore
        assert rig.models[0].executions == before
        assert rig.models[1].executions == (
            Counter({Opcode.EULER_CONTROL: 1, Opcode.ZOOM_TO: 1}) if restore else Counter())

    run(main())


def test_a_restore_that_fails_is_reported_and_not_retried() -> None:
    """The GCU comes back as a Z-6A, which has no zoom-to (Appendix 8): the mode is
    restored, the zoom fails, an ERROR link event and a WARNING say so."""

    async def main() -> None:
        rig = Rig(restore=True)
        async with rig.server, rig.gcu as gcu:
            await put_out_of_defaults(gcu)
            await rig.drop(20.0, restart="Z-6A")
            await gcu.wait_link(True, timeout=10.0)
            await asyncio.sleep(10.0)
            status = gcu.status
            assert status is not None and status.mode is Mode.EULER_CONTROL
        errors = [e.detail for _, e in rig.events if e.kind is K.ERROR]
        assert len(errors) == 1
        assert errors[0].startswith("restoring zoom 5x after the GCU restarted failed: ")
        assert "ZOOM_TO" in errors[0]
        assert rig.models[1].executions == Counter({Opcode.EULER_CONTROL: 1,
                                                    Opcode.ZOOM_TO: 1})  # refused, once

    run(main())


def test_a_command_sent_on_hearing_of_the_restart_comes_after_the_restore() -> None:
    async def main() -> None:
        rig = Rig(restore=True)
        sent: list[asyncio.Task[Any]] = []

        def on_restart(event: LinkEvent) -> None:
            if event.kind is K.RESTARTED:
                sent.append(asyncio.ensure_future(rig.gcu.enter_top_down()))

        rig.gcu.on_link_change(on_restart)
        async with rig.server, rig.gcu as gcu:
            await put_out_of_defaults(gcu)
            await rig.drop(20.0, restart=POD)
            await gcu.wait_link(True, timeout=10.0)
            await asyncio.sleep(10.0)
            await sent[0]
            status = gcu.status
            assert status is not None and status.mode is Mode.TOP_DOWN  # the application's
        log = rig.models[1].execution_log
        assert [int(e.command.OPCODE) for e in log] == [Opcode.EULER_CONTROL, Opcode.ZOOM_TO,
                                                        Opcode.TOP_DOWN]  # fmt: skip

    run(main())


# -- starting before the GCU ---------------------------------------------------------------
def test_status_and_info_are_none_before_the_first_reply() -> None:
    async def main() -> None:
        rig = Rig()
        gcu = rig.gcu
        assert (gcu.status, gcu.info) == (None, None)  # not opened
        rig.sim.silence(2.0)  # the first reply comes within connect_timeout (3 s)
        opening = asyncio.ensure_future(gcu.open())
        async with rig.server:
            await asyncio.sleep(1.0)
            assert gcu.state is ClientState.OPENING and (gcu.status, gcu.info) == (None, None)
            await opening
            assert gcu.status is not None and gcu.info is not None
            await gcu.close()

    run(main())



def test_wait_false_returns_at_once_and_the_link_comes_up_when_the_transport_opens() -> None:
    async def main() -> None:
        rig = Rig(opens_at=20.0, wait=False)
        async with rig.server, rig.gcu as gcu:
            assert rig.loop.time() == 0.0
            assert gcu.state is ClientState.OPENING
            assert (gcu.status, gcu.info, gcu.link.up) == (None, None, False)
            with pytest.raises(CommandLinkLost, match="client is opening") as info:
                await gcu.take_photo()
            assert info.value.outcome is Outcome.NOT_SENT
            await gcu.wait_link(True, timeout=60.0)
            assert 20.0 <= rig.loop.time() <= 20.0 + 5.0 + 0.1  # the backoff is capped at 5 s
            assert gcu.state is ClientState.OPEN and gcu.status is not None
            await gcu.take_photo()
        kinds = rig.kinds()
        assert kinds[-1] is K.UP and set(kinds[:-1]) == {K.RETRYING}
        assert len(kinds) - 1 == rig.gate.refused >= 5
        first = rig.events[0][1].detail
        assert first.startswith("attempt 1 failed: gate://gcu: cannot connect: refused; next in ")
        assert rig.executed() == Counter({Opcode.TAKE_PHOTO: 1})

    run(main())


def test_wait_false_against_a_silent_gcu_keeps_trying() -> None:
    """UDP's case: the transport opens, nothing answers until the GCU is powered."""

    async def main() -> None:
        rig = Rig(wait=False, connect_timeout=3.0)
        rig.sim.silence(40.0)
        async with rig.server, rig.gcu as gcu:
            await gcu.wait_link(True, timeout=60.0)
            assert 40.0 <= rig.loop.time() <= 40.0 + 3.0 + 5.0 + 0.1
        retrying = [e.detail for _, e in rig.events if e.kind is K.RETRYING]
        assert retrying and all("no reply from the GCU within 3 s" in d for d in retrying)
        assert rig.kinds()[-1] is K.UP

    run(main())


def test_waits_and_telemetry_started_before_the_gcu_answers_span_the_attempts() -> None:
    async def main() -> None:
        rig = Rig(opens_at=30.0, wait=False)
        async with rig.server, rig.gcu as gcu:
            stream = gcu.telemetry()
            first = asyncio.ensure_future(anext(stream))
            waiting = asyncio.ensure_future(gcu.wait_for(lambda s: True, timeout=100.0))
            sample = await waiting
            assert sample.received_at >= 30.0
            assert (await first).received_at >= 30.0
            await stream.aclose()

    run(main())


def test_open_timeout_inf_waits_as_long_as_it_takes() -> None:
    async def main() -> None:
        rig = Rig(opens_at=1000.0, open_timeout=math.inf)
        assert rig.gcu.open_timeout == math.inf
        async with rig.server, rig.gcu as gcu:
            assert rig.loop.time() >= 1000.0 and gcu.state is ClientState.OPEN

    run(main())


def test_wait_false_with_open_timeout_gives_up_and_fails() -> None:
    async def main() -> None:
        rig = Rig(opens_at=1e9, wait=False, open_timeout=30.0)
        async with rig.server:
            await rig.gcu.open()
            ended = asyncio.ensure_future(rig.gcu.wait_link(True, timeout=100.0))
            with pytest.raises(LinkLost, match="the client failed"):
                await ended
            assert 29.0 <= rig.loop.time() <= 30.0 + 0.1
            assert rig.gcu.state is ClientState.FAILED
            assert rig.gcu.failure is not None
            assert "no GCU within open_timeout 30 s" in rig.gcu.failure
            assert rig.kinds()[-1] is K.GAVE_UP
            assert rig.events[-1][1].detail == rig.gcu.failure
            await rig.gcu.close()
            assert rig.gcu.state is ClientState.CLOSED and rig.gcu.failure is None

    run(main())


# -- giving up ------------------------------------------------------------------------------
def test_a_transport_that_gives_up_fails_the_client_which_opens_again_later() -> None:
    async def main() -> None:
        rig = Rig(opens_at=0.0)
        async with rig.server:
            gcu = rig.gcu
            await gcu.open()
            rig.sim.silence(5.0)  # the command below stays in flight
            photo = asyncio.ensure_future(gcu.take_photo())
            waiting = asyncio.ensure_future(gcu.wait_for(lambda s: False, timeout=100.0))
            stream = gcu.telemetry()
            await asyncio.sleep(0.1)
            await rig.gate.give_up()
            with pytest.raises(CommandLinkLost) as info:
                await photo
            assert info.value.outcome is Outcome.UNKNOWN
            with pytest.raises(LinkLost, match=r"^the client failed \(giving up after "):
                await waiting
            assert [s async for s in stream] == []  # the iterator ends
            assert gcu.state is ClientState.FAILED
            assert gcu.failure == "giving up after 3 reconnect attempts (gate://gcu)"
            assert rig.kinds()[-2:] == [K.LOST, K.GAVE_UP]
            with pytest.raises(CommandLinkLost, match=r"client failed \(giving up after "):
                await gcu.take_photo()
            with pytest.raises(LinkLost, match="the client failed"):
                await gcu.wait_link(True)
            await asyncio.sleep(10.0)
            await gcu.open()  # the same client, once the GCU is back
            assert gcu.state is ClientState.OPEN and gcu.failure is None
            await gcu.take_photo()
            await gcu.close()
            assert gcu.state is ClientState.CLOSED

    run(main())


# -- logging -----------------------------------------------------------------------------
def test_a_long_outage_logs_a_few_lines_by_meaning(caplog: pytest.LogCaptureFixture) -> None:
    """A 47 s drop: the heartbeat's send fails 50 times a second (2,359 DEBUG lines before
    they were rate-limited); the loss is a WARNING, the recovery INFO."""

    async def main() -> None:
        rig = Rig()
        async with rig.server, rig.gcu as gcu:
            await rig.drop(47.0)
            await gcu.wait_link(True, timeout=10.0)
        assert gcu.link.send_errors >= 47 * 40

    with caplog.at_level(logging.DEBUG, logger="gcu_async.client"):
        run(main())
    lines = [r for r in caplog.records if r.name == "gcu_async.client"]
    sends = [r for r in lines if r.getMessage().startswith("send failed: ")]
    summaries = [r for r in lines if "more send failed lines suppressed" in r.getMessage()]
    assert 4 <= len(sends) <= 6 and len(summaries) <= 5, [r.getMessage() for r in lines]
    assert {r.levelno for r in sends + summaries} == {logging.DEBUG}
    level = {r.getMessage(): r.levelno for r in lines}
    assert level["link to memory://client up"] == logging.INFO
    assert level["link to memory://client restored"] == logging.INFO
    lost = [m for m in level if m.startswith("link to memory://client lost")]
    assert [level[m] for m in lost] == [logging.WARNING]


def test_an_hour_of_failed_attempts_logs_two_lines_a_minute(
        caplog: pytest.LogCaptureFixture) -> None:  # fmt: skip
    async def main() -> Rig:
        rig = Rig(opens_at=3600.0, wait=False)
        async with rig.server, rig.gcu as gcu:
            await gcu.wait_link(True, timeout=4000.0)
        return rig

    with caplog.at_level(logging.DEBUG, logger="gcu_async.client"):
        rig = run(main())
    attempts = [m for r in caplog.records if "attempt" in (m := r.getMessage())]
    retries = rig.kinds().count(K.RETRYING)
    assert retries >= 3600 / 5  # every attempt is an event
    assert len(attempts) <= 2 * 60 + 2, len(attempts)
    assert all(r.levelno == logging.INFO for r in caplog.records if "attempt" in r.getMessage())
