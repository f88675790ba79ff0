"""End to end on loopback: a pymavlink ground station drives the simulated XF gimbal
through the bridge's gimbal component (Gimbal Protocol v2)."""

from __future__ import annotations

import math

import pytest

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.geometry import euler_from_quaternion
from gcu_async.protocol.enums import Mode
from helpers.bridge.rig import GCS, GIMBAL, NAN, SYSTEM, bridge_rig

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED


async def test_discovery_answers_broadcast_requests_for_gimbal_information() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        hb = await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == GIMBAL, new=False)
        assert hb.type == mavlink.MAV_TYPE_GIMBAL and hb.get_srcSystem() == SYSTEM
        gcs.messages.clear()
        gcs.command(0, mavlink.MAV_CMD_REQUEST_MESSAGE,
                    mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION)  # broadcast, as MAVSDK
        ack = await gcs.ack(GIMBAL, mavlink.MAV_CMD_REQUEST_MESSAGE)
        assert ack.result == ACCEPTED and (ack.target_system, ack.target_component) == GCS
        info = await gcs.wait("GIMBAL_MANAGER_INFORMATION", new=False)
        assert info.gimbal_device_id == 1
        assert info.cap_flags & mavlink.GIMBAL_MANAGER_CAP_FLAGS_HAS_YAW_LOCK
        assert info.cap_flags & mavlink.GIMBAL_MANAGER_CAP_FLAGS_CAN_POINT_LOCATION_GLOBAL
        assert math.degrees(info.pitch_min) == pytest.approx(-180.0)
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_REQUEST_MESSAGE,
                            mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_INFORMATION)
        assert ack.result == ACCEPTED
        dev = await gcs.wait("GIMBAL_DEVICE_INFORMATION", new=False)
        assert dev.vendor_name == "XF Robot" and dev.model_name == "D-90Pro(TA)"
        # the versions the GCU reports (document firmware: 5.0, 3.1; the Z-1Pro's: 6.7, 0.1)
        # as MAVLink packs them: major in the low byte, minor in the next
        reported = rig.bridge.client.info
        assert reported is not None
        for field, version in ((dev.firmware_version, reported.firmware_version_raw),
                               (dev.hardware_version, reported.hardware_version_raw)):
            assert field == version // 10 | version % 10 << 8, (field, version)
        assert dev.gimbal_device_id == 1


async def test_status_streams_at_their_rates() -> None:
    async with bridge_rig() as rig:
        msgs = await rig.gcs.collect(1.0)
        kinds = [m.get_type() for m in msgs]
        assert kinds.count("GIMBAL_DEVICE_ATTITUDE_STATUS") >= 9  # 10 Hz, ~1 s
        assert 4 <= kinds.count("GIMBAL_MANAGER_STATUS") <= 6  # 5 Hz
        att = next(m for m in msgs if m.get_type() == "GIMBAL_DEVICE_ATTITUDE_STATUS")
        assert att.failure_flags == 0
        assert att.flags & mavlink.GIMBAL_DEVICE_FLAGS_YAW_IN_VEHICLE_FRAME  # no INS feed yet


async def test_pitchyaw_command_with_yaw_lock_sets_euler_angles() -> None:
    async with bridge_rig() as rig:
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                -30.0, 40.0, NAN, NAN, mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK)
        assert ack.result == ACCEPTED
        assert rig.state.mode is Mode.EULER_CONTROL
        await rig.until(lambda: abs(rig.state.attitude.pitch + 30.0) < 0.5
                        and abs(rig.state.attitude.yaw - 40.0) < 0.5, what="camera at -30/40")
        att = await rig.gcs.wait(
            "GIMBAL_DEVICE_ATTITUDE_STATUS",
            lambda m: abs(euler_from_quaternion(m.q).pitch + 30.0) < 0.5)
        assert att.flags & mavlink.GIMBAL_DEVICE_FLAGS_YAW_LOCK
        status = await rig.gcs.wait("GIMBAL_MANAGER_STATUS")
        assert status.flags & mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK
        # a second request of the same kind only moves the target: no new mode command
        before = rig.sim.model.executions[0x14]
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                -10.0, 20.0, NAN, NAN, mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK)
        assert ack.result == ACCEPTED
        await rig.until(lambda: abs(rig.state.attitude.pitch + 10.0) < 0.5, what="pitch -10")
        assert rig.sim.model.executions[0x14] == before


async def test_pitchyaw_rates_without_yaw_lock_follow() -> None:
    async with bridge_rig() as rig:
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                NAN, NAN, -5.0, 10.0, 0)
        assert ack.result == ACCEPTED
        assert rig.state.mode is Mode.POINTING_FOLLOW
        start = rig.state.relative.pitch
        await rig.until(lambda: rig.state.relative.pitch < start - 1.0, what="pitching down")


async def test_pitchyaw_out_of_range_is_denied_and_changes_nothing() -> None:
    async with bridge_rig() as rig:
        before = dict(rig.sim.model.executions)
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                NAN, NAN, -500.0, 0.0, 0)  # beyond 150 deg/s
        assert ack.result == mavlink.MAV_RESULT_DENIED
        ack = await rig.gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                                -30.0, 0.0, NAN, NAN, 0, 0, 3)  # gimbal device 3
        assert ack.result == mavlink.MAV_RESULT_DENIED
        assert dict(rig.sim.model.executions) == before


async def test_set_attitude_messages_move_the_gimbal() -> None:
    from gcu_async.bridge.geometry import quaternion_from_euler

    async with bridge_rig() as rig:
        gcs = rig.gcs
        q = quaternion_from_euler(0.0, -20.0, 30.0)
        gcs.send(mavlink.MAVLink_gimbal_manager_set_attitude_message(
            SYSTEM, GIMBAL, mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK, 0, q, NAN, NAN, NAN))
        await rig.until(lambda: rig.state.mode is Mode.EULER_CONTROL
                        and abs(rig.state.attitude.pitch + 20.0) < 0.5
                        and abs(rig.state.attitude.yaw - 30.0) < 0.5, what="euler -20/30")
        gcs.send(mavlink.MAVLink_gimbal_manager_set_pitchyaw_message(
            SYSTEM, GIMBAL, 0, 0, math.radians(-45.0), math.radians(10.0), NAN, NAN))
        await rig.until(lambda: rig.state.mode is Mode.ANGLE_CONTROL
                        and abs(rig.state.relative.pitch + 45.0) < 0.5
                        and abs(rig.state.relative.yaw - 10.0) < 0.5, what="angle -45/10")
        q = quaternion_from_euler(0.0, -60.0, 0.0)
        gcs.send(mavlink.MAVLink_gimbal_device_set_attitude_message(
            SYSTEM, GIMBAL, mavlink.GIMBAL_DEVICE_FLAGS_ROLL_LOCK, q, NAN, NAN, NAN))
        await rig.until(lambda: abs(rig.state.relative.pitch + 60.0) < 0.5, what="pitch -60")
        # rates only, yaw lock: pointing lock turning right
        gcs.send(mavlink.MAVLink_gimbal_manager_set_attitude_message(
            SYSTEM, GIMBAL, mavlink.GIMBAL_MANAGER_FLAGS_YAW_LOCK, 0, [NAN] * 4, NAN, 0.0,
            math.radians(20.0)))
        await rig.until(lambda: rig.state.mode is Mode.POINTING_LOCK, what="pointing lock")
        yaw = rig.state.attitude.yaw
        await rig.until(lambda: (rig.state.attitude.yaw - yaw) % 360 > 3.0, what="turning")


async def test_configure_gives_control_and_others_are_denied() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE, -2, -2, -1, -1)
        assert ack.result == ACCEPTED
        status = await gcs.wait("GIMBAL_MANAGER_STATUS")
        assert (status.primary_control_sysid, status.primary_control_compid) == GCS
        # the autopilot peer is not in control
        rig.autopilot.messages.clear()
        rig.autopilot.command(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, -30, 0)
        ack = await rig.autopilot.ack(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW)
        assert ack.result == mavlink.MAV_RESULT_DENIED
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_CONFIGURE, -3, -3, -1, -1)
        assert ack.result == ACCEPTED
        status = await gcs.wait("GIMBAL_MANAGER_STATUS")
        assert status.primary_control_sysid == 0


async def test_unknown_commands_are_unsupported_and_other_components_ignored() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        ack = await gcs.run(GIMBAL, mavlink.MAV_CMD_NAV_TAKEOFF)
        assert ack.result == mavlink.MAV_RESULT_UNSUPPORTED
        gcs.messages.clear()
        gcs.command(mavlink.MAV_COMP_ID_AUTOPILOT1, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                    -30.0, 0.0)
        gcs.command(GIMBAL, mavlink.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW, -30.0, 0.0,
                    system=SYSTEM + 1)
        msgs = await gcs.collect(0.5)
        assert not [m for m in msgs if m.get_type() == "COMMAND_ACK"]
        assert rig.state.mode is Mode.POINTING_FOLLOW  # untouched
