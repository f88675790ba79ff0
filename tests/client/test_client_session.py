"""Session behaviour with a scripted GCU: what goes into each packet, errors, queueing."""

from __future__ import annotations

import asyncio
import time
import warnings
from collections.abc import AsyncIterator

import pytest

from gcu_async import (
    CommandFailed,
    CommandTimeout,
    Feedback,
    GcuClient,
    LinkLost,
    Opcode,
    UnsupportedCommandError,
)
from gcu_async.protocol import (
    CameraMask,
    GcuSubFrame,
    HostPacket,
    HostSubFrame,
    TakePhoto,
    command_code,
)
from helpers.session.fake_gcu import FakeGcu, succeed


@pytest.fixture
async def fake() -> AsyncIterator[FakeGcu]:
    gcu = FakeGcu()
    await gcu.start()
    yield gcu
    await gcu.stop()


async def until(predicate: object, timeout: float = 2.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():  # type: ignore[operator]
        assert time.monotonic() < deadline, "timed out"
        await asyncio.sleep(0.005)


def last(fake: FakeGcu) -> HostPacket:
    return fake.packets[-1]


async def test_aircraft_state_never_invented(fake: FakeGcu) -> None:
    async with GcuClient(fake.client_end) as gcu:
        p = last(fake)
        assert not p.main.ins_valid
        assert not p.main.control_valid
        assert p.sub is None
        assert p.main.subframe_request == 1
        gcu.update_aircraft(attitude=(1.5, -2.0, 350.0), velocity=(1.0, 2.0, -0.5))
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        p = last(fake)
        assert not p.main.ins_valid  # no acceleration yet: nothing claimed, zeros sent
        assert p.main.aircraft_attitude == (0.0, 0.0, 0.0)
        assert p.main.velocity == (0.0, 0.0, 0.0)
        assert not gcu.ins_valid
        gcu.update_aircraft(acceleration=(0.0, 0.0, 0.0))
        assert gcu.ins_valid
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        p = last(fake)
        assert p.main.ins_valid
        assert p.main.aircraft_attitude == (1.5, -2.0, 350.0)
        assert p.main.velocity == (1.0, 2.0, -0.5)
        assert p.sub is None  # no position given: no sub frame
        gcu.update_aircraft(attitude=(1.5, -2.0, 350.0), velocity=(1.0, 2.0, -0.5),
                            acceleration=(0.0, 0.0, 0.0),  # still current: given again
                            position=(47.3977418, 8.5455938, 488.0), relative_altitude=30.0)
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        sub = last(fake).sub
        assert isinstance(sub, HostSubFrame)
        assert sub.latitude_raw == 473977418
        assert sub.relative_altitude == 30.0
        assert last(fake).main.ins_valid
        gcu.update_aircraft(attitude=None)
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        assert not last(fake).main.ins_valid


async def test_control_values_valid_bit_and_invalid_during_centre(fake: FakeGcu) -> None:
    centre_packets: list[HostPacket] = []

    def answer(packet: HostPacket) -> Feedback | None:
        if command_code(packet.command) == Opcode.CENTRE:
            centre_packets.append(packet)
            if len(centre_packets) < 3:
                return None  # centre takes a few packets
        return succeed(packet)

    fake.answer = answer
    async with GcuClient(fake.client_end) as gcu:
        await gcu.enter_pointing_lock(pitch_rate=-2.0)
        gcu.set_rates(pitch=-4.0, yaw=1.0)
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        assert last(fake).main.control_valid
        assert last(fake).main.control.as_rates() == (0.0, -4.0, 1.0)
        await gcu.centre()
        assert len(centre_packets) >= 3
        assert all(not p.main.control_valid for p in centre_packets)
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        # the old rates would steer away from the centre: cleared, sent invalid
        assert gcu.control is None
        assert not last(fake).main.control_valid
        gcu.set_rates(yaw=2.0)  # the mode is unchanged: new rates go out valid
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        assert last(fake).main.control_valid


async def test_mode_helper_sends_control_invalid_until_mode_confirmed(fake: FakeGcu) -> None:
    async with GcuClient(fake.client_end) as gcu:
        await gcu.enter_pointing_lock(yaw_rate=5.0)
        await gcu.enter_euler_control(pitch=-45.0, yaw=270.0)
        euler = [p for p in fake.packets if command_code(p.command) == Opcode.EULER_CONTROL]
        assert euler
        assert all(not p.main.control_valid for p in euler)  # rates never read as angles
        # yaw 270 is sent as -90 (the control field is ±180)
        assert gcu.control is not None
        assert gcu.control.as_angles() == (0.0, -45.0, -90.0)
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        assert last(fake).main.control_valid
        assert last(fake).main.control.as_angles() == (0.0, -45.0, -90.0)


async def test_command_goes_out_at_once_not_at_the_next_tick(fake: FakeGcu) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        client = GcuClient(fake.client_end, rate_hz=2.0)  # a tick every 0.5 s
    async with client as gcu:
        await asyncio.sleep(0.6)  # mid-way between ticks, with room in the rate bound
        start = time.monotonic()
        await asyncio.wait_for(gcu.take_photo(), 1.0)
        assert time.monotonic() - start < 0.4
        assert gcu.session.stats.early_packets == 1


async def test_failure_raises_command_failed_with_cameras(fake: FakeGcu) -> None:
    fake.answer = lambda p: (
        Feedback(Opcode.ZOOM_TO, 0x03) if command_code(p.command) == Opcode.ZOOM_TO else succeed(p)
    )
    async with GcuClient(fake.client_end) as gcu:
        with pytest.raises(CommandFailed) as info:
            await gcu.zoom_to(5.0, cameras=CameraMask.CAMERA_1 | CameraMask.CAMERA_2)
        assert info.value.opcode == Opcode.ZOOM_TO
        assert info.value.status == 0x03
        assert info.value.failed_cameras == CameraMask.CAMERA_1 | CameraMask.CAMERA_2
        assert "ZOOM_TO" in str(info.value)


async def test_unmatched_feedback_counted_not_given_to_waiter(fake: FakeGcu) -> None:
    fake.answer = lambda p: (
        Feedback(Opcode.FOCUS, 0) if command_code(p.command) == Opcode.TAKE_PHOTO else succeed(p)
    )
    async with GcuClient(fake.client_end) as gcu:
        with pytest.raises(CommandTimeout) as info:
            await gcu.execute(TakePhoto(), timeout=0.2)
        assert isinstance(info.value, TimeoutError)
        assert gcu.link.unmatched_feedback > 0
        # the session is consistent afterwards
        fake.answer = succeed
        await gcu.take_photo()


async def test_in_progress_keeps_waiting(fake: FakeGcu) -> None:
    calls = 0

    def answer(packet: HostPacket) -> Feedback | None:
        nonlocal calls
        if command_code(packet.command) == Opcode.CALIBRATION:
            calls += 1
            return Feedback(Opcode.CALIBRATION, 0x02 if calls < 10 else 0x00)
        return succeed(packet)

    fake.answer = answer
    async with GcuClient(fake.client_end) as gcu:
        feedback = await gcu.calibrate(timeout=3.0)
        assert feedback.status == 0
        assert calls >= 10


async def test_concurrent_callers_complete_in_fifo_order(fake: FakeGcu) -> None:
    async with GcuClient(fake.client_end) as gcu:
        order: list[int] = []

        calls = (gcu.take_photo, gcu.focus, gcu.stop_zoom)

        async def call(i: int) -> None:
            await calls[i % 3]()
            order.append(i)

        await asyncio.gather(*(call(i) for i in range(30)))
        assert order == list(range(30))
        commands = [command_code(p.command) for p in fake.packets if command_code(p.command)]
        # one command per packet, and each distinct call shows up in submission order
        runs = [op for i, op in enumerate(commands) if i == 0 or op != commands[i - 1]]
        assert len(runs) == 30


async def test_cancelled_call_leaves_session_consistent(fake: FakeGcu) -> None:
    silent = True
    # the GCU answers heartbeats but not commands while ``silent``
    fake.answer = lambda p: (None if silent and command_code(p.command) else succeed(p))
    async with GcuClient(fake.client_end, silence_timeout=5.0) as gcu:
        task = asyncio.create_task(gcu.take_photo())
        queued = asyncio.create_task(gcu.focus())
        await asyncio.sleep(0.1)
        task.cancel()
        queued.cancel()
        with pytest.raises(asyncio.CancelledError):
            await task
        with pytest.raises(asyncio.CancelledError):
            await queued
        assert gcu.session.pending == 0
        silent = False
        await asyncio.wait_for(gcu.take_photo(), 2.0)


async def test_check_support_refuses_without_sending(fake: FakeGcu) -> None:
    fake.sub = GcuSubFrame.build(pod_model=0)  # Z-6A: no palette, no zoom-to
    async with GcuClient(fake.client_end, check_support=True) as gcu:
        await until(lambda: gcu.pod_model is not None)
        submitted = gcu.session.stats.submitted
        with pytest.raises(UnsupportedCommandError, match="Z-6A does not support PALETTE"):
            await gcu.set_palette(2)
        assert gcu.session.stats.submitted == submitted
        assert all(command_code(p.command) != Opcode.PALETTE for p in fake.packets)
        await gcu.take_photo()  # not in Appendix 8: every model


async def test_no_reply_at_open_is_link_lost() -> None:
    fake = FakeGcu(answer=lambda p: None)
    await fake.start()
    try:
        client = GcuClient(fake.client_end, connect_timeout=0.2)
        with pytest.raises(LinkLost, match="no reply"):
            await client.open()
        assert not fake.client_end.connected
    finally:
        await fake.stop()


def test_rate_validation() -> None:
    """(A bad ``rate_hz`` or ``version`` alone: test_client_builder.py, "options checked
    once".)"""
    a, _ = FakeGcu().client_end, None
    # a heartbeat slower than the silence timeout would lose the link between packets
    with pytest.raises(
        ValueError,
        match=r"silence_timeout: 0\.5 .*\[0\.5, inf\] s \(must exceed the heartbeat period",
    ):
        GcuClient(a, rate_hz=2.0, silence_timeout=0.5)
    with pytest.warns(UserWarning, match="30-50 Hz"):
        GcuClient(a, rate_hz=2.0, silence_timeout=0.51)
    with pytest.warns(UserWarning, match="30-50 Hz"):
        GcuClient(a, rate_hz=20)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        GcuClient(a, rate_hz=40)
    for name in ("command_timeout", "connect_timeout"):
        with pytest.raises(ValueError, match=name):
            GcuClient(a, **{name: 0})


def test_built_frames_hold_plain_integers() -> None:
    from gcu_async.protocol import ControlValues, HostMainFrame

    frame = HostMainFrame.build(control=ControlValues.angles(pitch=-10), attitude=(0, 0, 0),
                                acceleration=(0, 0, 0), velocity=(0, 0, 0))
    assert type(frame.flags_raw) is int
    assert frame.flags_raw == 0x05


async def test_click_to_pan_and_track_release_the_control_values(fake: FakeGcu) -> None:
    async with GcuClient(fake.client_end) as gcu:
        await gcu.enter_euler_control(pitch=-30.0)
        await gcu.click_to_pan(0.8, 0.2)
        assert gcu.control is None  # pointing-lock would read angle targets as rates
        n = len(fake.packets)
        await until(lambda: len(fake.packets) > n + 1)
        assert not last(fake).main.control_valid
        with pytest.raises(ValueError, match="no mode is confirmed"):
            gcu.set_angles(pitch=-30.0)
        await gcu.enter_euler_control(pitch=-30.0)
        await gcu.track((0.4, 0.4, 0.6, 0.6))
        assert gcu.control is None
        with pytest.raises(ValueError, match="TRACK takes no control values"):
            gcu.set_angles(pitch=-30.0)
