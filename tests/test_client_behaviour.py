"""One behavioural suite for the client, run over every transport against the simulator.

Uses the project's own pytest plugin fixtures (``gcu_sim``, ``gcu_client``), parametrized
over in-memory, UDP, TCP and serial (a real pty).
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from _catalogue_samples import required_samples
from gcu_async import CommandFailed, GcuClient, LinkLost, Mode, Opcode
from gcu_async.protocol import (
    CameraFlags,
    ExecutionStatus,
    NightVisionMode,
    PodStatus,
    ThermalFlags,
)
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.pods import supports
from gcu_async.pytest_plugin import TRANSPORTS, SimHandle
from gcu_async.sim import DEFAULT_POD


@pytest.fixture(params=TRANSPORTS)
def gcu_sim_transport(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def gcu_sim_model_options() -> dict[str, Any]:
    return {"calibration_seconds": 0.3}


async def wait_for(
    predicate: Callable[[], bool], timeout: float = 3.0, what: str = "condition"
) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}")
        await asyncio.sleep(0.01)


Call = Callable[[GcuClient], Awaitable[Any]]
# (call, opcode) for every command the default pod (D-90Pro(TA)) supports
ROUND_TRIPS: list[tuple[str, Call, Opcode]] = [
    ("centre", lambda g: g.centre(), Opcode.CENTRE),
    ("enter_euler_control", lambda g: g.enter_euler_control(pitch=-10.0, yaw=20.0),
     Opcode.EULER_CONTROL),
    ("enter_angle_control", lambda g: g.enter_angle_control(pitch=-5.0, yaw=5.0),
     Opcode.ANGLE_CONTROL),
    ("enter_fpv", lambda g: g.enter_fpv(pitch=-5.0), Opcode.FPV),
    ("enter_pointing_lock", lambda g: g.enter_pointing_lock(yaw_rate=2.0), Opcode.POINTING_LOCK),
    ("enter_pointing_follow", lambda g: g.enter_pointing_follow(), Opcode.POINTING_FOLLOW),
    ("enter_top_down", lambda g: g.enter_top_down(), Opcode.TOP_DOWN),
    ("enter_gaze_lock", lambda g: g.enter_gaze_lock(), Opcode.GAZE_LOCK),
    ("gaze_at", lambda g: g.gaze_at(47.39, 8.54, 420.0), Opcode.GAZE_AT_COORDINATES),
    ("track", lambda g: g.track((0.4, 0.4, 0.6, 0.6)), Opcode.TRACK),
    ("stop_tracking", lambda g: g.stop_tracking(), Opcode.TRACK),
    ("click_to_pan", lambda g: g.click_to_pan(0.7, 0.3), Opcode.CLICK_TO_PAN),
    ("take_photo", lambda g: g.take_photo(), Opcode.TAKE_PHOTO),
    ("toggle_recording", lambda g: g.toggle_recording(), Opcode.RECORD),
    ("zoom_in", lambda g: g.zoom_in(), Opcode.ZOOM_IN),
    ("stop_zoom", lambda g: g.stop_zoom(), Opcode.ZOOM_STOP),
    ("zoom_out", lambda g: g.zoom_out(), Opcode.ZOOM_OUT),
    ("zoom_to", lambda g: g.zoom_to(4.0), Opcode.ZOOM_TO),
    ("zoom_to_fraction", lambda g: g.zoom_to_fraction(0.5), Opcode.ZOOM_TO),
    ("focus", lambda g: g.focus(), Opcode.FOCUS),
    ("set_palette", lambda g: g.set_palette(3), Opcode.PALETTE),
    ("set_night_vision", lambda g: g.set_night_vision(NightVisionMode.AUTO), Opcode.NIGHT_VISION),
    ("set_area_temperature", lambda g: g.set_area_temperature(True, (0.1, 0.1, 0.5, 0.5)),
     Opcode.AREA_TEMPERATURE),
    ("set_temperature_alarm", lambda g: g.set_temperature_alarm(True, high=80.0, low=-10.0),
     Opcode.TEMPERATURE_ALARM),
    ("set_isotherm", lambda g: g.set_isotherm(True, high=60.0, low=20.0), Opcode.ISOTHERM),
    ("set_spot_temperature", lambda g: g.set_spot_temperature(True, 0.5, 0.5),
     Opcode.SPOT_TEMPERATURE),
    ("set_osd", lambda g: g.set_osd(True), Opcode.OSD),
    ("set_osd_coordinates", lambda g: g.set_osd_coordinates(1), Opcode.OSD_COORDINATES),
    ("set_image_auto_flip", lambda g: g.set_image_auto_flip(False), Opcode.IMAGE_AUTO_FLIP),
    ("set_time_zone", lambda g: g.set_time_zone(-5), Opcode.TIME_ZONE),
    ("set_picture_in_picture", lambda g: g.set_picture_in_picture(2), Opcode.PICTURE_IN_PICTURE),
    ("set_target_detection", lambda g: g.set_target_detection(True), Opcode.TARGET_DETECTION),
    ("set_digital_zoom", lambda g: g.set_digital_zoom(True), Opcode.DIGITAL_ZOOM),
    ("set_ranging", lambda g: g.set_ranging(True), Opcode.RANGING),
    ("calibrate", lambda g: g.calibrate(timeout=10.0), Opcode.CALIBRATION),
]
STATE_CHECKED = {"start_recording", "stop_recording"}
"""Sent or not by the recording flag: tests/test_client_waiting.py and the web example's."""
ROUND_TRIPS += [  # the rest of the catalogue with its samples: a new command runs here unlisted
    (e.method, lambda g, e=e: getattr(g, e.method)(**required_samples(e)), e.opcode)
    for e in CATALOGUE
    if e.method not in {name for name, _, _ in ROUND_TRIPS} | STATE_CHECKED
    and supports(DEFAULT_POD, e.opcode)
]
"""(method, call, opcode) for every command method the default pod (D-90Pro(TA)) supports."""


async def hover(gcu: GcuClient, period: float = 0.1) -> None:
    """Keep the aircraft data current (until cancelled): level, at rest, at one position."""
    while True:
        gcu.update_aircraft(attitude=(0.0, 0.0, 0.0), acceleration=(0.0, 0.0, 0.0),
                            velocity=(0.0, 0.0, 0.0), position=(47.39, 8.54, 500.0))  # fmt: skip
        await asyncio.sleep(period)


async def test_every_command_round_trip(gcu_sim: SimHandle, gcu_client: GcuClient) -> None:
    model = gcu_sim.simulator.model
    # gaze needs valid aircraft INS data and position, current all along
    feed = asyncio.create_task(hover(gcu_client))
    expected: dict[int, int] = {}
    try:
        for name, call, opcode in ROUND_TRIPS:
            feedback = await call(gcu_client)
            assert feedback.opcode == opcode, name
            assert feedback.result is ExecutionStatus.SUCCESS, name
            expected[opcode] = expected.get(opcode, 0) + 1
    finally:
        feed.cancel()
    # every command ran exactly once on the GCU (nothing twice, nothing skipped)
    assert {op: model.executions[op] for op in expected} == expected
    assert {name for name, _, _ in ROUND_TRIPS} | STATE_CHECKED == {
        e.method for e in CATALOGUE if supports(DEFAULT_POD, e.opcode)
    }
    # the one Appendix 8 command this pod lacks answers with the failure status
    with pytest.raises(CommandFailed) as info:
        await gcu_client.set_fill_light(100)
    assert info.value.opcode == Opcode.FILL_LIGHT
    assert info.value.status == 0x01


async def test_telemetry_follows_the_gimbal(gcu_sim: SimHandle, gcu_client: GcuClient) -> None:
    g = gcu_client
    g.update_aircraft(attitude=(0.0, 0.0, 90.0), acceleration=(0.0, 0.0, 0.0),
                      velocity=(0.0, 0.0, 0.0))  # the simulator keeps the last valid one
    await g.enter_euler_control(pitch=-30.0, yaw=120.0)
    await wait_for(lambda: g.status.mode is Mode.EULER_CONTROL, what="euler mode")
    await wait_for(
        lambda: abs(g.status.attitude.pitch + 30) < 0.5 and abs(g.status.attitude.yaw - 120) < 0.5,
        timeout=5.0,
        what="camera at pitch -30, yaw 120",
    )
    await g.zoom_to(6.0)
    await wait_for(lambda: abs(g.info.camera1_zoom - 6.0) < 0.05, timeout=5.0, what="zoom 6x")
    assert not g.info.recording
    await g.start_recording()
    await wait_for(lambda: g.info.recording, what="recording flag")
    assert CameraFlags.RECORDING in g.info.camera_flags
    await g.stop_recording()
    await wait_for(lambda: not g.info.recording, what="recording stopped")
    await g.set_ranging(True)
    await wait_for(lambda: PodStatus.RANGING_ON in g.status.pod_status, what="ranging flag")
    await g.set_area_temperature(True)
    await wait_for(
        lambda: ThermalFlags.AREA_TEMPERATURE_ON in g.info.thermal_flags, what="thermal flag"
    )
    assert g.info.pod_model.name == "D_90PRO_TA"
    link = g.link
    assert link.up
    assert link.packets_received > 0
    assert link.crc_errors == 0
    assert link.last_reply_age is not None
    assert link.last_reply_age < 0.5


async def test_telemetry_iterator_is_bounded_newest_wins(gcu_client: GcuClient) -> None:
    stream = gcu_client.telemetry(maxsize=2)
    first = await asyncio.wait_for(stream.__anext__(), 2.0)
    await asyncio.sleep(0.3)  # fall behind: the queue keeps only the newest two
    second = await asyncio.wait_for(stream.__anext__(), 2.0)
    assert second.received_at > first.received_at
    assert gcu_client.telemetry_dropped > 0
    await stream.aclose()


async def test_clean_shutdown_leaves_nothing_running(gcu_sim: SimHandle) -> None:
    before = {t for t in asyncio.all_tasks() if not t.done()}
    client = gcu_sim.client()
    async with client as gcu:
        await gcu.take_photo()
        gcu_sim.silence(5.0)  # the next command cannot complete before the client closes
        pending = asyncio.ensure_future(gcu.zoom_to(3.0))
        await asyncio.sleep(0.05)
        assert not pending.done()
    # closing failed the waiting command at once instead of leaving it hanging
    with pytest.raises(LinkLost):
        await asyncio.wait_for(pending, 1.0)
    after = {t for t in asyncio.all_tasks() if not t.done()}
    assert after <= before | {asyncio.current_task()}
    assert not client.transport.connected
    with pytest.raises(LinkLost):
        await client.take_photo()
