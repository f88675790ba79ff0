"""End to end on loopback: a pymavlink ground station uses the bridge's camera component
(Camera Protocol v2) on the simulated pod."""

from __future__ import annotations

import math

from gcu_async.bridge._mavlink import mavlink
from gcu_async.protocol.enums import Mode, Opcode
from helpers.bridge.rig import CAMERA, GCS, bridge_rig

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
UNSUPPORTED = mavlink.MAV_RESULT_UNSUPPORTED
REQUEST = mavlink.MAV_CMD_REQUEST_MESSAGE


async def test_discovery_and_every_requested_message() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        hb = await gcs.wait("HEARTBEAT", lambda m: m.get_srcComponent() == CAMERA, new=False)
        assert hb.type == mavlink.MAV_TYPE_CAMERA
        ack = await gcs.run(CAMERA, REQUEST, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
        assert ack.result == ACCEPTED and (ack.target_system, ack.target_component) == GCS
        info = await gcs.wait("CAMERA_INFORMATION", new=False)
        assert bytes(info.vendor_name).rstrip(b"\0") == b"XF Robot"
        assert bytes(info.model_name).rstrip(b"\0") == b"D-90Pro(TA)"
        for flag in ("CAPTURE_IMAGE", "CAPTURE_VIDEO", "HAS_BASIC_ZOOM", "HAS_BASIC_FOCUS",
                     "HAS_VIDEO_STREAM", "HAS_TRACKING_POINT", "HAS_TRACKING_RECTANGLE"):
            assert info.flags & getattr(mavlink, f"CAMERA_CAP_FLAGS_{flag}"), flag
        # the deprecated request command still works
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1)
        assert ack.result == ACCEPTED
        await gcs.wait("CAMERA_INFORMATION", new=False)
        expected = {
            "CAMERA_SETTINGS": lambda m: m.mode_id == 0 and abs(m.zoomLevel - 100 / 30) < 0.01,
            "CAMERA_CAPTURE_STATUS": lambda m: m.video_status == 0 and m.image_count == 0,
            "STORAGE_INFORMATION": lambda m: m.status == mavlink.STORAGE_STATUS_NOT_SUPPORTED,
            "VIDEO_STREAM_INFORMATION": lambda m: m.uri == "rtsp://127.0.0.1:8554/main"
                                                  and m.type == mavlink.VIDEO_STREAM_TYPE_RTSP,
            "CAMERA_TRACKING_IMAGE_STATUS": lambda m: m.tracking_status == 0,
            "CAMERA_FOV_STATUS": lambda m: m.lat_image == 2**31 - 1,  # no aircraft yet
        }
        for name, check in expected.items():
            ack = await gcs.run(CAMERA, REQUEST, getattr(mavlink, f"MAVLINK_MSG_ID_{name}"))
            assert ack.result == ACCEPTED, name
            assert check(await gcs.wait(name, new=False)), name
        ack = await gcs.run(CAMERA, REQUEST, mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_INFORMATION)
        assert ack.result == UNSUPPORTED  # the gimbal's message, not the camera's


async def test_photo_is_taken_and_announced() -> None:
    async with bridge_rig() as rig:
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 1)
        assert ack.result == ACCEPTED
        assert rig.state.camera.photos == {1: 1}
        shot = await rig.gcs.wait("CAMERA_IMAGE_CAPTURED", new=False)
        assert shot.capture_result == 1 and shot.image_index == 0
        assert shot.lat == 0 and shot.time_utc == 0  # no autopilot feed: no geotag
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 2)
        shot = await rig.gcs.wait("CAMERA_IMAGE_CAPTURED", new=False)
        assert shot.image_index == 1 and rig.state.camera.photos == {1: 2}
        status = await rig.gcs.wait("CAMERA_CAPTURE_STATUS", lambda m: m.image_count == 2)
        assert status.image_status == 0
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 2, 0)
        assert ack.result == UNSUPPORTED  # interval capture
        assert rig.state.camera.photos == {1: 2}


async def test_video_start_and_stop_are_idempotent_over_the_toggle() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        for _ in range(2):
            ack = await gcs.run(CAMERA, mavlink.MAV_CMD_VIDEO_START_CAPTURE, 0, 0)
            assert ack.result == ACCEPTED
            assert rig.state.camera.recording
        assert rig.sim.model.executions[Opcode.RECORD] == 1
        status = await gcs.wait("CAMERA_CAPTURE_STATUS", lambda m: m.video_status == 1)
        settings = await gcs.wait("CAMERA_SETTINGS")
        assert settings.mode_id == mavlink.CAMERA_MODE_VIDEO
        later = await gcs.wait("CAMERA_CAPTURE_STATUS",
                               lambda m: m.recording_time_ms > status.recording_time_ms)
        assert later.video_status == 1
        for _ in range(2):
            ack = await gcs.run(CAMERA, mavlink.MAV_CMD_VIDEO_STOP_CAPTURE, 0)
            assert ack.result == ACCEPTED
            assert not rig.state.camera.recording
        assert rig.sim.model.executions[Opcode.RECORD] == 2
        await gcs.wait("CAMERA_CAPTURE_STATUS", lambda m: m.video_status == 0)


async def test_zoom_continuous_range_and_step() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        zoom = mavlink.MAV_CMD_SET_CAMERA_ZOOM
        assert (await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_CONTINUOUS, 1)).result == ACCEPTED
        await rig.until(lambda: rig.state.zoom[1] > 3.0, what="zooming in")
        assert (await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_CONTINUOUS, 0)).result == ACCEPTED
        held = rig.state.zoom[1]
        assert rig.state.camera.zoom[1].target is None and held < 30.0
        assert (await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_RANGE, 50)).result == ACCEPTED
        await rig.until(lambda: abs(rig.state.zoom[1] - 15.0) < 0.05, what="zoom 15x")
        await gcs.wait("CAMERA_SETTINGS", lambda m: abs(m.zoomLevel - 50.0) < 0.5)
        assert (await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_STEP, -2)).result == ACCEPTED
        await rig.until(lambda: abs(rig.state.zoom[1] - 13.0) < 0.05, what="zoom 13x")
        ack = await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_FOCAL_LENGTH, 35)
        assert ack.result == UNSUPPORTED
        ack = await gcs.run(CAMERA, zoom, mavlink.ZOOM_TYPE_RANGE, 150)
        assert ack.result == mavlink.MAV_RESULT_DENIED


async def test_focus_source_and_tracking() -> None:
    async with bridge_rig() as rig:
        gcs = rig.gcs
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_FOCUS, mavlink.FOCUS_TYPE_AUTO)
        assert ack.result == ACCEPTED and rig.state.camera.focus_count == 1
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_FOCUS, mavlink.FOCUS_TYPE_METERS, 5)
        assert ack.result == UNSUPPORTED and rig.state.camera.focus_count == 1
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_SOURCE, 0, mavlink.CAMERA_SOURCE_IR,
                            mavlink.CAMERA_SOURCE_RGB)
        assert ack.result == ACCEPTED and rig.state.camera.pip_mode == 2
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, 0.4, 0.4, 0.6, 0.6)
        assert ack.result == ACCEPTED and rig.state.mode is Mode.TRACK
        status = await gcs.wait("CAMERA_TRACKING_IMAGE_STATUS", lambda m: m.tracking_status
                                == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
        assert status.tracking_mode == mavlink.CAMERA_TRACKING_MODE_RECTANGLE
        assert 0.0 <= status.point_x <= 1.0 and 0.0 <= status.point_y <= 1.0
        assert math.isnan(status.radius)
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_CAMERA_STOP_TRACKING)
        assert ack.result == ACCEPTED and rig.state.mode is not Mode.TRACK
        await gcs.wait("CAMERA_TRACKING_IMAGE_STATUS", lambda m: m.tracking_status
                       == mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE)
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_CAMERA_TRACK_POINT, 0.5, 0.5, 0.1)
        assert ack.result == ACCEPTED and rig.state.mode is Mode.TRACK
        status = await gcs.wait("CAMERA_TRACKING_IMAGE_STATUS", lambda m: m.tracking_status
                                == mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE)
        assert status.tracking_mode == mavlink.CAMERA_TRACKING_MODE_POINT
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_CAMERA_TRACK_POINT, 1.5, 0.5, 0.1)
        assert ack.result == mavlink.MAV_RESULT_DENIED


async def test_camera_mode_is_accepted_and_reported() -> None:
    async with bridge_rig() as rig:
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_MODE, 0,
                                mavlink.CAMERA_MODE_VIDEO)
        assert ack.result == ACCEPTED
        await rig.gcs.wait("CAMERA_SETTINGS", lambda m: m.mode_id == mavlink.CAMERA_MODE_VIDEO)
        assert not rig.state.camera.recording


async def test_non_thermal_pod_refuses_what_appendix_8_lacks() -> None:
    async with bridge_rig("Z-6C", max_zoom=None, video_url=None) as rig:
        gcs = rig.gcs
        await rig.until(lambda: rig.bridge.view().pod_model is not None, what="pod model")
        ack = await gcs.run(CAMERA, REQUEST, mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
        info = await gcs.wait("CAMERA_INFORMATION", new=False)
        assert bytes(info.model_name).rstrip(b"\0") == b"Z-6C"
        assert not info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
        assert not info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
        before = dict(rig.sim.model.executions)
        for command, params in [
            (mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE, (0.4, 0.4, 0.6, 0.6)),
            (mavlink.MAV_CMD_CAMERA_TRACK_POINT, (0.5, 0.5, 0.1)),
            (mavlink.MAV_CMD_SET_CAMERA_SOURCE, (0, mavlink.CAMERA_SOURCE_IR, 0)),
            (mavlink.MAV_CMD_SET_CAMERA_ZOOM, (mavlink.ZOOM_TYPE_RANGE, 50)),
            (REQUEST, (mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION,)),
        ]:
            ack = await gcs.run(CAMERA, command, *params)
            assert ack.result == UNSUPPORTED, command
        assert dict(rig.sim.model.executions) == before
        ack = await gcs.run(CAMERA, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1, 1)
        assert ack.result == ACCEPTED and rig.state.camera.photos == {1: 1}
        await gcs.wait("CAMERA_SETTINGS", lambda m: math.isnan(m.zoomLevel))


async def test_zoom_to_unsupported_model_the_client_refuses_too() -> None:
    """Before the bridge knows the model it cannot refuse; the client's check_support does
    once the model is known, and either way the answer is UNSUPPORTED, never FAILED."""
    async with bridge_rig("Z-6C") as rig:
        ack = await rig.gcs.run(CAMERA, mavlink.MAV_CMD_SET_CAMERA_ZOOM, mavlink.ZOOM_TYPE_STEP, 1)
        assert ack.result == UNSUPPORTED
        assert rig.sim.model.executions[Opcode.ZOOM_TO] == 0
