"""One behavioural suite for the client, run over every transport against the simulator.

Uses the project's own pytest plugin fixtures (``gcu_sim``, ``gcu_client``), parametrized
over in-memory, UDP, TCP and serial (a real pty).
"""

from __future__ import annotations

import asyncio
import time
from collections import Counter
from collections.abc import Callable
from typing import Any

import pytest

from gcu_async import CommandFailed, GcuClient, LinkLost, Mode
from gcu_async.protocol import (
    CameraFlags,
    ExecutionStatus,
    NightVisionMode,
    PodStatus,
    ThermalFlags,
)
from gcu_async.protocol.catalogue import CATALOGUE, CatalogueEntry
from gcu_async.protocol.pods import supports
from gcu_async.pytest_plugin import TRANSPORTS, SimHandle
from helpers.protocol.catalogue_samples import required_samples


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


ARGUMENTS: dict[str, dict[str, Any]] = {
    "enter_euler_control": {"pitch": -10.0, "yaw": 20.0},
    "enter_angle_control": {"pitch": -5.0, "yaw": 5.0},
    "enter_fpv": {"pitch": -5.0},
    "enter_pointing_lock": {"yaw_rate": 2.0},
    "calibrate": {"timeout": 10.0},
    "set_palette": {"palette": 3},
    "set_night_vision": {"mode": NightVisionMode.AUTO},
    "set_area_temperature": {"box": (0.1, 0.1, 0.5, 0.5)},
    "set_temperature_alarm": {"high": 80.0, "low": -10.0},
    "set_isotherm": {"high": 60.0, "low": 20.0},
    "set_osd_coordinates": {"coordinates": 1},
    "set_image_auto_flip": {"enabled": False},
    "set_picture_in_picture": {"mode": 2},
}
"""Values other than the defaults, where they make the command do more."""


FIRST, LAST = ("centre",), ("calibrate",)
"""Centre works in the default mode (pointing-lock), not after a gaze; calibration last."""
ORDER = sorted(CATALOGUE, key=lambda e: (e.method not in FIRST, e.method in LAST))
"""The catalogue's order, but for FIRST and LAST."""


def arguments(entry: CatalogueEntry) -> dict[str, Any]:
    given = required_samples(entry)
    return {**given, **ARGUMENTS.get(entry.method, {})}


async def hover(gcu: GcuClient, period: float = 0.1) -> None:
    """Keep the aircraft data current (until cancelled): level, at rest, at one position."""
    while True:
        gcu.update_aircraft(attitude=(0.0, 0.0, 0.0), acceleration=(0.0, 0.0, 0.0),
                            velocity=(0.0, 0.0, 0.0), position=(47.39, 8.54, 500.0))  # fmt: skip
        await asyncio.sleep(period)


async def test_every_command_round_trip(gcu_sim: SimHandle, gcu_client: GcuClient) -> None:
    """Every catalogue entry, through its client method, in ORDER: the pod
    (D-90Pro(TA)) runs each command it supports exactly once and answers the others with
    the failure status; a state-checked record command that is not needed sends nothing."""
    model = gcu_sim.simulator.model
    await gcu_client.wait_for(lambda s: s.info is not None, timeout=3.0, what="a sub frame")
    pod = gcu_client.pod_model
    assert pod is not None
    # gaze needs valid aircraft INS data and position, current all along
    feed = asyncio.create_task(hover(gcu_client))
    expected: Counter[int] = Counter()
    unsupported = []
    try:
        for entry in ORDER:
            call = getattr(gcu_client, entry.method)(**arguments(entry))
            if not supports(pod, entry.opcode):
                with pytest.raises(CommandFailed) as info:
                    await call
                assert info.value.opcode == entry.opcode
                assert info.value.status == 0x01
                unsupported.append(entry.method)
                continue
            feedback = await call
            if feedback is None:  # start/stop_recording with the camera already there
                assert entry.method in ("start_recording", "stop_recording"), entry.method
                continue
            assert feedback.opcode == entry.opcode, entry.method
            assert feedback.result is ExecutionStatus.SUCCESS, entry.method
            expected[entry.opcode] += 1
    finally:
        feed.cancel()
    assert unsupported == ["set_fill_light"]  # the one Appendix 8 command this pod lacks
    assert set(expected) == {e.opcode for e in CATALOGUE if supports(pod, e.opcode)}
    # every command ran exactly once on the GCU (nothing twice, nothing skipped)
    assert {op: model.executions[op] for op in expected} == dict(expected)


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
