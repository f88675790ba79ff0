"""Commands and setpoints while the GCU is not answering (docs/mavlink-bridge.md, "The bridge
contract", BG4 and BG9): while the client opens or the GCU is silent, a command waits within
its 2 s for the GCU, then is carried out or answered TEMPORARILY_REJECTED — never ACCEPTED
for a setpoint the GCU never got (PITCHYAW was, in a field report), never rejected at once
because the link was not up yet, never sent after its 2 s. Real loopback sockets, a pymavlink
ground station, the simulator going silent."""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import pytest

from gcu_async.bridge import MavlinkBridge, admission
from gcu_async.bridge._mavlink import mavlink
from gcu_async.client.connect import connect
from gcu_async.protocol.commands import GazeAtCoordinates, PointingFollow, TakePhoto
from gcu_async.protocol.enums import Mode
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.sim import GcuSimulator, SimulatorModel
from helpers.bridge.rig import CAMERA, GCS, GIMBAL, NAN, Peer, Rig, bridge_rig

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
PITCHYAW = mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW
PHOTO = mavlink.MAV_CMD_IMAGE_START_CAPTURE
YAW_LOCK = mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK
INTO_SILENCE = 0.3
"""Seconds into the GCU's silence the request is sent: the session still counts the link up
(its silence timeout is 1 s), the GCU has not answered for 0.3 s."""
SILENCE = INTO_SILENCE + admission.COMMAND_WAIT + 0.7
"""Long enough that a request sent INTO_SILENCE in outlives its 2 s before the GCU answers."""


def executed(rig: Rig, kind: type) -> int:
    return sum(isinstance(r.command, kind) for r in rig.sim.model.execution_log)


async def in_euler_control(rig: Rig) -> None:
    ack = await rig.gcs.run(GIMBAL, PITCHYAW, -20, 30, NAN, NAN, YAW_LOCK)
    assert ack.result == ACCEPTED
    await rig.until(lambda: rig.bridge.view().in_mode(Mode.EULER_CONTROL)
                    and rig.bridge.client.control_valid, what="Euler control, values valid")


async def back(rig: Rig) -> None:
    await rig.until(lambda: rig.bridge.view().link_up, SILENCE + 5.0, "GCU link back")


GIMBAL_REQUESTS: dict[str, tuple[tuple[float, ...], type | None]] = {
    # a setpoint (the pod is in the mode): only new control values, no GCU command
    "setpoint": ((10, -40, NAN, NAN, YAW_LOCK), None),
    # pitch/yaw with yaw follow: a mode command (angle control)
    "mode change": ((10, -40, NAN, NAN, 0), None),
    # region of interest: COMMAND_LONG altitude above home (the autopilot gave it)
    "roi location": ((0, 0, 0, 0, 22.5, 113.9, 30.0), GazeAtCoordinates),
    "roi none": ((0,), PointingFollow),
}


@pytest.mark.parametrize("request_name", list(GIMBAL_REQUESTS))
async def test_a_gimbal_request_while_the_gcu_is_silent_is_not_accepted(
        request_name: str) -> None:  # fmt: skip
    """Main: the setpoint was ACCEPTED at once (and applied when the GCU answered again);
    the mode change and the ROI commands went out to the silent GCU and ended FAILED
    (outcome unknown). Now each waits its 2 s and is TEMPORARILY_REJECTED, and nothing of
    it reaches the GCU when it answers again."""
    params, kind = GIMBAL_REQUESTS[request_name]
    command = {"roi location": mavlink.MAV_CMD_DO_SET_ROI_LOCATION,
               "roi none": mavlink.MAV_CMD_DO_SET_ROI_NONE}.get(request_name, PITCHYAW)
    async with bridge_rig() as rig:
        await rig.fly(seconds=0.3)  # home altitude and INS: the ROI command could run
        await in_euler_control(rig)
        control = rig.bridge.client.control
        runs = executed(rig, kind) if kind else 0
        rig.sim.silence(SILENCE)
        await rig.gcs.collect(INTO_SILENCE)
        sent = time.monotonic()
        ack = await rig.gcs.run(GIMBAL, command, *params,
                                timeout=admission.COMMAND_WAIT + 2.0)  # fmt: skip
        waited = time.monotonic() - sent
        assert ack.result == REJECTED, mavlink.enums["MAV_RESULT"][ack.result].name
        assert waited >= admission.COMMAND_WAIT - 0.05  # it waited for the GCU
        assert rig.bridge.client.control == control  # the setpoint was not taken
        await back(rig)
        await rig.gcs.collect(0.3)
        assert rig.bridge.client.control == control  # nor when the GCU answers again
        assert rig.state.mode is Mode.EULER_CONTROL
        if kind:
            assert executed(rig, kind) == runs


async def test_control_messages_wait_for_the_gcu_within_the_bound() -> None:
    """A GIMBAL_MANAGER_SET_PITCHYAW message while the GCU is silent: one that outlives its
    2 s is never applied; one sent less than 2 s before the GCU answers again is applied
    then. Main applied both at once, while the GCU was silent."""
    async with bridge_rig() as rig:
        await in_euler_control(rig)
        client = rig.bridge.client
        control = client.control
        rig.sim.silence(SILENCE)

        def setpoint(pitch: float, yaw: float) -> None:
            rig.gcs.conn.mav.gimbal_manager_set_pitchyaw_send(
                1, GIMBAL, YAW_LOCK, 0, math.radians(pitch), math.radians(yaw), NAN, NAN)

        await rig.gcs.collect(INTO_SILENCE)
        setpoint(10, -40)
        await rig.gcs.collect(admission.COMMAND_WAIT + 0.2)
        assert client.control == control
        setpoint(5, 60)  # 0.5 s before the GCU answers again
        await back(rig)
        await rig.until(lambda: client.control == ControlValues.angles(0, 5, 60), 2.0,
                        "the second setpoint applied")  # fmt: skip
        assert rig.bridge.stats["expired"] == 1  # the first one


async def test_a_command_during_a_short_silence_runs_when_the_gcu_answers_again() -> None:
    """Main sent the photo to the silent GCU: FAILED (outcome unknown) once the link was
    declared lost. Now it waits, and runs once the GCU answers within its 2 s."""
    async with bridge_rig() as rig:
        photos = executed(rig, TakePhoto)
        rig.sim.silence(1.5)
        await rig.gcs.collect(INTO_SILENCE)
        ack = await rig.gcs.run(CAMERA, PHOTO, 0, 0, 1, timeout=admission.COMMAND_WAIT + 2.0)
        assert ack.result == ACCEPTED
        assert executed(rig, TakePhoto) == photos + 1


async def opening_bridge(silence: float) -> Any:
    """A simulator silent for ``silence`` s, a client whose first open attempt outlasts it,
    the bridge, and a ground station that has its (CRITICAL) heartbeat."""
    sim = GcuSimulator(SimulatorModel("D-90Pro(TA)", record_executions=True))
    gcs = Peer(*GCS)
    server = sim.serve_udp("127.0.0.1", 0)
    await server.open()
    sim.silence(silence)
    client = connect(server.url, local_port=0, connect_timeout=silence + 2.0)
    bridge = MavlinkBridge(client, [gcs.url])
    await bridge.start()
    hb = await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL)
    assert hb.system_status == mavlink.MAV_STATE_CRITICAL
    return sim, server, bridge, gcs


@pytest.mark.parametrize(("silence", "result"), [(1.0, ACCEPTED), (3.0, REJECTED)])
async def test_a_command_while_the_client_opens_waits_within_the_bound(
        silence: float, result: int, caplog: pytest.LogCaptureFixture) -> None:  # fmt: skip
    """Main answered TEMPORARILY_REJECTED at once while the client was opening (and logged
    why only with -v, in numbers). Now a photo waits: the GCU answering within its 2 s takes
    it (ACCEPTED, executed); one answering later never gets it (TEMPORARILY_REJECTED after
    2 s, not before, never executed; a warning says why, by name)."""
    sim, server, bridge, gcs = await opening_bridge(silence)
    try:
        sent = time.monotonic()
        ack = await gcs.run(CAMERA, PHOTO, 0, 0, 1, timeout=admission.COMMAND_WAIT + 2.0)
        waited = time.monotonic() - sent
        assert ack.result == result, mavlink.enums["MAV_RESULT"][ack.result].name
        if result == REJECTED:
            assert waited >= admission.COMMAND_WAIT - 0.05
            assert [r.levelno for r in caplog.records if r.getMessage().startswith(
                "bridge: MAV_CMD_IMAGE_START_CAPTURE from 255/190")] == [logging.WARNING]
            assert ("MAV_RESULT_TEMPORARILY_REJECTED: not sent within 2 s: the GCU link is "
                    "not open yet") in caplog.text
            await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                           and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=5.0)
            await gcs.collect(0.3)
        runs = [r for r in sim.model.execution_log if isinstance(r.command, TakePhoto)]
        assert len(runs) == (1 if result == ACCEPTED else 0)
    finally:
        await bridge.close()
        await server.close()
        gcs.close()
