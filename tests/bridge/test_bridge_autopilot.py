"""End to end on loopback: a pymavlink fake autopilot feeds the GCU's heartbeat through the
bridge; the region of interest, geotags and the field-of-view target depend on it; link
losses on either side are reported and heal; hostile MAVLink input changes nothing."""

from __future__ import annotations

import asyncio
import math
import random

import pytest

from gcu_async.bridge._mavlink import mavlink
from gcu_async.protocol.enums import Mode
from helpers.bridge.rig import CAMERA, GIMBAL, HOME_MSL, SYSTEM, bridge_rig

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
EARTH = mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_EARTH_FRAME
VEHICLE = mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME


async def test_autopilot_stream_reaches_the_gcu_and_goes_stale_when_it_stops() -> None:
    async with bridge_rig() as rig:
        await rig.fly(lat=22.5, lon=113.9, relative_alt=100.0, yaw=30.0, seconds=0.3)
        client = rig.bridge.client
        await rig.until(lambda: rig.state.aircraft.ins_valid, what="INS valid at the GCU")
        assert client.ins_valid
        aircraft = rig.state.aircraft
        assert aircraft.position is not None
        assert aircraft.position.latitude == pytest.approx(22.5, abs=1e-6)
        assert aircraft.position.altitude == pytest.approx(HOME_MSL + 100.0, abs=0.01)
        assert aircraft.relative_altitude == pytest.approx(100.0, abs=0.01)
        assert aircraft.attitude.yaw == pytest.approx(30.0, abs=0.01)
        assert aircraft.satellites == 12 and aircraft.gnss_week > 0
        att = await rig.gcs.wait("GIMBAL_DEVICE_ATTITUDE_STATUS", lambda m: m.flags & EARTH)
        assert not math.isnan(att.delta_yaw)
        # the autopilot goes quiet: after aircraft_timeout (1 s) nothing is claimed
        await rig.until(lambda: not client.ins_valid, timeout=3.0, what="stale feed")
        await rig.until(lambda: not rig.state.aircraft.ins_valid, what="INS invalid at the GCU")
        await rig.gcs.wait("GIMBAL_DEVICE_ATTITUDE_STATUS", lambda m: m.flags & VEHICLE)
        assert client.session.stats.aircraft_stale >= 1
        # the MAVLink link to the autopilot is reported lost after 3 s of silence
        link = rig.bridge.links[1]
        assert link.up
        await rig.until(lambda: not link.up, timeout=5.0, what="autopilot link lost")
        await rig.fly()
        await rig.until(lambda: link.up, what="autopilot link restored")


async def test_region_of_interest_needs_the_feed_and_releases() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        roi = mavlink.MAV_CMD_DO_SET_ROI_LOCATION
        # no feed: COMMAND_LONG heights are above home, which is unknown yet
        ack = await gcs.run(GIMBAL, roi, 0, 0, 0, 0, 22.501, 113.9, 0.0)
        assert ack.result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        # MSL via COMMAND_INT reaches the GCU, which refuses to gaze without INS data
        gcs.messages.clear()
        gcs.conn.mav.command_int_send(SYSTEM, GIMBAL, mavlink.MAV_FRAME_GLOBAL_INT, roi, 0, 0,
                                      0, 0, 0, 0, 225_010_000, 1_139_000_000, HOME_MSL)
        ack = await gcs.ack(GIMBAL, roi)
        assert ack.result == mavlink.MAV_RESULT_FAILED and ack.result_param2 == 0x01
        feeding = asyncio.ensure_future(rig.fly(seconds=4.0))
        try:
            await rig.until(lambda: rig.bridge.client.ins_valid, what="INS valid")
            ack = await gcs.run(GIMBAL, roi, 0, 0, 0, 0, 22.501, 113.9, 0.0)
            assert ack.result == ACCEPTED and rig.state.mode is Mode.GAZE
            # 111 m north, 100 m below: the camera looks north and down ~42 degrees
            await rig.until(lambda: abs(rig.state.attitude.pitch + 41.9) < 1.0
                            and abs((rig.state.attitude.yaw + 180) % 360 - 180) < 1.0,
                            what="looking at the point")  # fmt: skip
            fov = await gcs.wait("CAMERA_FOV_STATUS", lambda m: m.lat_image != 2**31 - 1)
            assert fov.lat_image / 1e7 == pytest.approx(22.501, abs=2e-5)  # ~2 m
            assert fov.alt_image / 1000 == pytest.approx(HOME_MSL, abs=0.01)
            assert fov.lat_camera == 225_000_000
            ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_DO_SET_ROI_NONE)
            assert ack.result == ACCEPTED and rig.state.mode is Mode.POINTING_FOLLOW
        finally:
            feeding.cancel()


async def test_photos_are_geotagged_from_the_autopilot() -> None:
    async with bridge_rig() as rig:
        feeding = asyncio.ensure_future(rig.fly(lat=-33.86, lon=151.2, relative_alt=60.0,
                                                seconds=3.0))  # fmt: skip
        try:
            await rig.until(lambda: rig.bridge.client.ins_valid, what="INS valid")
            ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 1)
            assert ack.result == ACCEPTED
            shot = await rig.gcs.wait("CAMERA_IMAGE_CAPTURED", new=False)
        finally:
            feeding.cancel()
        assert (shot.lat, shot.lon) == (-338_600_000, 1_512_000_000)
        assert shot.alt == round((HOME_MSL + 60.0) * 1000) and shot.relative_alt == 60_000
        assert shot.time_utc > 1_700_000_000_000_000
        assert all(math.isfinite(c) for c in shot.q)


async def test_gcu_link_loss_is_reported_and_heals() -> None:
    async with bridge_rig() as rig:
        rig.gcs.messages.clear()
        # long enough that the command below, which waits up to 2 s for the GCU, ends while
        # the GCU is still silent (the loss is seen 1 s in, the 1 Hz heartbeat says so)
        rig.sim.silence(8.0)
        hb = await rig.gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                                and m.system_status == mavlink.MAV_STATE_CRITICAL, timeout=4.0)
        assert hb.type == mavlink.MAV_TYPE_GIMBAL
        att = await rig.gcs.wait("GIMBAL_DEVICE_ATTITUDE_STATUS", lambda m: m.failure_flags
                                 & mavlink.GIMBAL_DEVICE_ERROR_FLAGS_COMMS_ERROR, new=False)
        assert att is not None
        # a command while the GCU is silent is not sent and says "try again"
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_FOCUS, mavlink.FOCUS_TYPE_AUTO,
                                timeout=8.0)
        assert ack.result == mavlink.MAV_RESULT_TEMPORARILY_REJECTED
        assert rig.state.camera.focus_count == 0
        await rig.gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                           and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=10.0)
        await rig.gcs.wait("GIMBAL_DEVICE_ATTITUDE_STATUS", lambda m: m.failure_flags == 0)
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, -20, 0)
        assert ack.result == ACCEPTED


async def test_hostile_mavlink_input_never_stops_the_bridge() -> None:
    rng = random.Random(11)
    async with bridge_rig() as rig:
        gcs = rig.gcs
        for _ in range(200):  # garbage, including stray MAVLink start bytes
            gcs.conn.write(bytes(rng.getrandbits(8) for _ in range(rng.randint(1, 300)))
                           + b"\xfd" * rng.randint(0, 3))
        mav = gcs.conn.mav
        for command in (mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, mavlink.MAV_CMD_REQUEST_MESSAGE,
                        mavlink.MAV_CMD_SET_CAMERA_ZOOM, mavlink.MAV_CMD_CAMERA_TRACK_POINT,
                        mavlink.MAV_CMD_DO_SET_ROI_LOCATION, mavlink.MAV_CMD_SET_CAMERA_SOURCE,
                        mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE):
            for target in (GIMBAL, CAMERA):
                for value in (math.nan, math.inf, -math.inf, 3e38, -1.0):
                    mav.command_long_send(SYSTEM, target, command, 0, *[value] * 7)
        for value in (math.nan, math.inf, 1e30):
            mav.gimbal_manager_set_attitude_send(SYSTEM, GIMBAL, 0xFFFFFFFF, 0, [value] * 4,
                                                 value, value, value)  # fmt: skip
            mav.gimbal_manager_set_pitchyaw_send(SYSTEM, GIMBAL, 0, 0, value, value, value,
                                                 value)  # fmt: skip
            mav.gimbal_device_set_attitude_send(SYSTEM, GIMBAL, 0xFFFF, [value, 0, 0, 0],
                                                value, value, value)  # fmt: skip
        # the autopilot sends values no field can carry
        apm = rig.autopilot.conn.mav
        apm.attitude_send(0, math.nan, math.inf, 1e30, 0, 0, 0)
        apm.local_position_ned_send(0, 0, 0, 0, 1e6, 0, 0)
        apm.local_position_ned_send(10, 0, 0, 0, -1e6, 0, 0)
        apm.global_position_int_send(0, 2_000_000_000, 2_000_000_000, 0, 0, 0, 0, 0, 0)
        apm.system_time_send(1, 0)
        await gcs.collect(0.5)
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_REQUEST_MESSAGE,
                            mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION)
        assert ack.result == ACCEPTED
        assert rig.bridge.stats["handler_errors"] == 0
        assert rig.bridge.links[0].bad_data > 0
        # and it still steers the gimbal
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                            -25, 0, math.nan, math.nan, mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK)
        assert ack.result == ACCEPTED
        await rig.until(lambda: abs(rig.state.attitude.pitch + 25) < 0.5, what="pitch -25")


async def test_long_commands_are_in_progress_first_and_retransmissions_run_once() -> None:
    async with bridge_rig(in_progress_after=0.1) as rig:
        gcs = rig.gcs
        gcs.messages.clear()
        rig.sim.stall(0.6)  # the GCU freezes: the command waits for its feedback
        focus = mavlink.MAV_CMD_SET_CAMERA_FOCUS
        gcs.command(CAMERA, focus, mavlink.FOCUS_TYPE_AUTO)
        first = await gcs.ack(CAMERA, focus, final=False)
        assert first.result == mavlink.MAV_RESULT_IN_PROGRESS and first.progress == 255
        # the station retransmits (MAVLink's rule: the same parameters, confirmation + 1)
        gcs.command(CAMERA, focus, mavlink.FOCUS_TYPE_AUTO, confirmation=1)
        final = await gcs.ack(CAMERA, focus)
        assert final.result == ACCEPTED
        await gcs.collect(0.3)
        acks = [m.result for m in gcs.messages if m.get_type() == "COMMAND_ACK"]
        assert acks.count(ACCEPTED) == 1 and mavlink.MAV_RESULT_IN_PROGRESS in acks
        assert rig.state.camera.focus_count == 1


async def test_autopilot_state_for_gimbal_device_feeds_attitude_and_velocity() -> None:
    from gcu_async.bridge.geometry import quaternion_from_euler

    async with bridge_rig() as rig:
        q = quaternion_from_euler(2.0, -3.0, 123.0)
        for _ in range(5):
            rig.autopilot.conn.mav.autopilot_state_for_gimbal_device_send(
                SYSTEM, GIMBAL, 0, q, 0, 4.0, -2.0, 1.0, 0, 0.0, 0, 0)
            await asyncio.sleep(0.05)
        aircraft = rig.bridge.client.aircraft
        assert aircraft.attitude == pytest.approx((2.0, -3.0, 123.0), abs=0.01)
        assert aircraft.velocity == pytest.approx((4.0, -2.0, -1.0))


async def test_a_gcu_that_answers_late_is_picked_up(caplog: pytest.LogCaptureFixture) -> None:
    from gcu_async.bridge import MavlinkBridge
    from gcu_async.client.connect import connect
    from gcu_async.sim import GcuSimulator
    from helpers.bridge.rig import GCS, Peer

    sim = GcuSimulator()
    gcs = Peer(*GCS)
    try:
        async with sim.serve_udp("127.0.0.1", 0) as server:
            sim.silence(1.0)  # not answering yet: the first open attempt fails
            client = connect(server.url, local_port=0, connect_timeout=0.5)
            async with MavlinkBridge(client, [gcs.url]):
                hb = await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL)
                assert hb.system_status == mavlink.MAV_STATE_CRITICAL
                await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL
                               and m.system_status == mavlink.MAV_STATE_ACTIVE, timeout=6.0)
        assert "GCU link not up yet" in caplog.text and "GCU link up" in caplog.text
    finally:
        gcs.close()


def test_bad_bridge_options_are_refused() -> None:
    from gcu_async.bridge import MavlinkBridge
    from gcu_async.client.connect import connect

    client = connect("udp://127.0.0.1:9")
    with pytest.raises(ValueError, match="connections"):
        MavlinkBridge(client, [])
    with pytest.raises(ValueError, match="system_id"):
        MavlinkBridge(client, ["udpout:127.0.0.1:9"], system_id=0)
    with pytest.raises(ValueError, match="in_progress_after"):
        MavlinkBridge(client, ["udpout:127.0.0.1:9"], in_progress_after=0)
