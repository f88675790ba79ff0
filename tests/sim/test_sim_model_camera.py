"""Sans-I/O SimulatorModel: zoom over time, camera/thermal flags, ranging, pod support."""

from __future__ import annotations

import pytest

from gcu_async.protocol import (
    AreaTemperature,
    CameraFlags,
    CameraMask,
    DigitalZoom,
    FillLight,
    HostSubFrame,
    ImageAutoFlip,
    ImageBox,
    ImagePoint,
    Isotherm,
    NightVision,
    NightVisionMode,
    Osd,
    OsdCoordinates,
    OsdCoordinateSource,
    Palette,
    PictureInPicture,
    PodStatus,
    Ranging,
    SpotTemperature,
    TargetDetection,
    TemperatureAlarm,
    ThermalFlags,
    TimeZone,
    TopDown,
    ZoomIn,
    ZoomOut,
    ZoomStop,
    ZoomTo,
)
from helpers.sim.support import Rig, sub_of

A = pytest.approx


def test_continuous_zoom_moves_over_time_within_range() -> None:
    rig = Rig()  # D-90Pro(TA): camera 1 is 1–30× (simulator assumption), ~4 s end to end
    assert sub_of(rig.command(ZoomIn())).camera1_zoom == 1.0
    seen = [sub_of(rig.run(0.5)).camera1_zoom for _ in range(4)]
    assert seen == sorted(seen)
    assert 1.0 < seen[0] < seen[-1] < 30.0
    assert seen[1] == A(1.0 + 29.0 / 4.0, abs=0.1)  # 7.25×/s for 1 s
    rig.command(ZoomStop())
    stopped = sub_of(rig.run(1.0)).camera1_zoom
    assert stopped == A(seen[-1], abs=0.1)
    rig.command(ZoomIn())
    assert sub_of(rig.run(10.0)).camera1_zoom == 30.0
    rig.command(ZoomOut())
    assert sub_of(rig.run(10.0)).camera1_zoom == 1.0


@pytest.mark.parametrize(
    ("command", "expected"),
    [
        (ZoomTo(ratio=12.5), 12.5),
        (ZoomTo(ratio=300.0), 30.0),  # beyond the pod: its maximum
        (ZoomTo(fraction=0.5), 15.0),  # the spec's example: 5000 → 15× on a 30× camera
        (ZoomTo(fraction=1.0), 30.0),
        (ZoomTo(fraction=0.0001), 1.0),
    ],
)
def test_zoom_to_ratio_reaches_its_target(command: ZoomTo, expected: float) -> None:
    rig = Rig()
    rig.command(command)
    halfway = sub_of(rig.run(0.5)).camera1_zoom
    assert halfway <= max(expected, 1.0 + 29.0 / 8.0 + 0.1)
    assert sub_of(rig.run(5.0)).camera1_zoom == A(expected)


def test_thermal_camera_zooms_on_its_own() -> None:
    rig = Rig()
    rig.command(ZoomIn(cameras=CameraMask.THERMAL))
    sub = rig.run(10.0).sub
    assert sub is not None
    assert (sub.camera1_zoom, sub.camera2_zoom) == (1.0, 8.0)


def test_max_zoom_is_configurable() -> None:
    rig = Rig(max_zoom=10.0)
    rig.command(ZoomTo(ratio=30.0))
    assert sub_of(rig.run(5.0)).camera1_zoom == 10.0


def test_digital_zoom_extends_the_range() -> None:
    rig = Rig()
    reply = rig.command(DigitalZoom(True))
    assert reply.sub is not None
    assert reply.sub.camera_flags & CameraFlags.DIGITAL_ZOOM_ON
    rig.command(ZoomTo(ratio=100.0))
    assert sub_of(rig.run(20.0)).camera1_zoom == 100.0
    rig.command(DigitalZoom(False))
    assert sub_of(rig.run(20.0)).camera1_zoom == 30.0


def test_zoom_fails_for_a_camera_the_pod_lacks() -> None:
    rig = Rig("Z-8RB")  # no thermal camera, 10× (simulator assumption for Z-series)
    reply = rig.command(ZoomIn(cameras=CameraMask.CAMERA_1 | CameraMask.CAMERA_2))
    assert reply.feedback.status == 0x02  # NN: camera 2 failed
    assert reply.feedback.failed_cameras == CameraMask.CAMERA_2
    sub = rig.run(5.0).sub
    assert sub is not None
    assert sub.camera1_zoom == 10.0
    assert sub.camera2_zoom == 0.0


def test_ranging_reports_distance_and_target_when_on() -> None:
    rig = Rig()
    rig.sub = HostSubFrame.build(latitude=38.0, longitude=117.0, altitude=200.0,
                                 relative_altitude=120.0)  # fmt: skip
    reply = rig.null()
    assert reply.sub is not None
    assert reply.sub.target_distance is None
    assert not reply.main.pod_status & (PodStatus.RANGING_ON | PodStatus.RANGE_VALID)
    reply = rig.command(Ranging(True))  # looking at the horizon: nothing in range
    assert reply.main.pod_status & PodStatus.RANGING_ON
    assert not reply.main.pod_status & PodStatus.RANGE_VALID
    assert reply.sub is not None
    assert reply.sub.target_distance_raw == -10
    rig.command(TopDown())
    reply = rig.run(1.5)
    assert reply.main.pod_status & PodStatus.RANGE_VALID
    assert reply.sub is not None
    assert reply.sub.target_distance == A(120.0, abs=0.3)
    target = reply.sub.target_position
    assert target.latitude == A(38.0, abs=1e-6)
    assert target.longitude == A(117.0, abs=1e-6)
    assert target.altitude == A(80.0, abs=0.01)
    reply = rig.command(Ranging(False))
    assert not reply.main.pod_status & (PodStatus.RANGING_ON | PodStatus.RANGE_VALID)
    assert reply.sub is not None
    assert reply.sub.target_distance_raw == 0


def test_ranging_noise_is_seeded() -> None:
    def distances(seed: int) -> list[int]:
        rig = Rig(seed=seed)
        rig.command(TopDown())
        rig.command(Ranging(True))
        rig.run(1.0)
        return [sub_of(rig.run(0.02)).target_distance_raw for _ in range(20)]

    assert distances(3) == distances(3)
    assert distances(3) != distances(4)
    assert all(abs(d - 1000) <= 2 for d in distances(5))  # 100 m default height, ±0.2 m


def test_fill_light_turns_night_vision_on_but_not_off() -> None:
    rig = Rig("Z-9B_V4(T)")  # supports the fill light (Appendix 8)
    reply = rig.command(FillLight(200))
    assert reply.feedback.status == 0
    assert reply.main.pod_status & PodStatus.FILL_LIGHT_ON
    assert reply.main.pod_status & PodStatus.NIGHT_VISION_ON
    reply = rig.command(FillLight(0))
    assert not reply.main.pod_status & PodStatus.FILL_LIGHT_ON
    assert reply.main.pod_status & PodStatus.NIGHT_VISION_ON
    reply = rig.command(NightVision(NightVisionMode.OFF))
    assert not reply.main.pod_status & PodStatus.NIGHT_VISION_ON
    reply = rig.command(NightVision(NightVisionMode.AUTO))  # the simulated scene is daylight
    assert not reply.main.pod_status & PodStatus.NIGHT_VISION_ON
    rig.model.state.camera.ambient_dark = True
    assert rig.null().main.pod_status & PodStatus.NIGHT_VISION_ON


def test_fill_light_fails_on_a_pod_without_one() -> None:
    rig = Rig()  # D-90Pro(TA): fill light ○
    reply = rig.command(FillLight(200))
    assert reply.feedback.status == 0x01
    assert not reply.main.pod_status & (PodStatus.FILL_LIGHT_ON | PodStatus.NIGHT_VISION_ON)


def test_thermal_commands_set_the_thermal_flags() -> None:
    rig = Rig()
    T = ThermalFlags
    assert sub_of(rig.null()).thermal_flags == T.MEASUREMENT_AVAILABLE
    rig.command(AreaTemperature(True, ImageBox(0.2, 0.2, 0.4, 0.4)))
    rig.command(SpotTemperature(True, ImagePoint(0.3, 0.3)))
    rig.command(Isotherm(True, high=30.0, low=20.0))
    flags = sub_of(rig.command(TemperatureAlarm(True, high=40.0, low=10.0))).thermal_flags
    # the simulated scene spans 15–45 °C: above the high threshold, not below the low one
    on = T.AREA_TEMPERATURE_ON | T.SPOT_TEMPERATURE_ON | T.ISOTHERM_ON | T.TEMPERATURE_ALARM_ON
    assert flags == T.MEASUREMENT_AVAILABLE | on | T.HIGH_TEMPERATURE_ALARM
    flags = sub_of(rig.command(TemperatureAlarm(True, high=50.0, low=20.0))).thermal_flags
    assert flags & T.LOW_TEMPERATURE_ALARM
    assert not flags & T.HIGH_TEMPERATURE_ALARM
    rig.command(AreaTemperature(False))
    rig.command(Isotherm(False))
    flags = sub_of(rig.command(TemperatureAlarm(False))).thermal_flags
    assert flags == T.MEASUREMENT_AVAILABLE | T.SPOT_TEMPERATURE_ON


def test_thermal_commands_need_the_thermal_camera() -> None:
    rig = Rig()
    assert rig.command(Palette(4, cameras=CameraMask.CAMERA_1)).feedback.status == 0x02
    assert rig.command(Palette(4)).feedback.status == 0x00
    assert rig.model.state.camera.palette == 4
    rig.command(Palette(0))  # 0 cycles
    assert rig.model.state.camera.palette == 5


@pytest.mark.parametrize("pod", ["Z-6A", "D-80Pro", "D-80AI"])
def test_thermal_commands_fail_on_models_without_thermal(pod: str) -> None:
    rig = Rig(pod)
    assert rig.command(Palette(2)).feedback.status == 0x02
    assert rig.command(AreaTemperature(True)).feedback.status == 0x02
    assert rig.command(TemperatureAlarm(True, high=40.0, low=0.0)).feedback.status == 0x02
    sub = rig.null().sub
    assert sub is not None
    assert sub.thermal_flags_raw == 0
    assert sub.camera2_zoom_raw == 0


def test_palette_works_on_a_non_radiometric_thermal_model() -> None:
    rig = Rig("D-125AI(V)")  # has a palette, no temperature measurement (Appendix 8)
    assert rig.command(Palette(2)).feedback.status == 0x00
    assert rig.command(SpotTemperature(True)).feedback.status == 0x02
    assert sub_of(rig.null()).thermal_flags_raw == 0


def test_unsupported_commands_fail_without_effect_on_z6a() -> None:
    rig = Rig("Z-6A")
    assert rig.command(TimeZone(8)).feedback.status == 0x01
    assert rig.command(Ranging(True)).feedback.status == 0x01
    assert rig.command(ZoomTo(ratio=5.0)).feedback.status == 0x01  # NN = camera 1
    assert rig.command(Osd(True)).feedback.status == 0x01
    sub = rig.run(2.0).sub
    assert sub is not None
    assert sub.time_zone == 0
    assert sub.camera1_zoom == 1.0
    assert not sub.camera_flags & CameraFlags.OSD_ON
    assert rig.command(ZoomIn()).feedback.status == 0x00  # continuous zoom: every model


def test_display_settings_show_in_the_camera_flags() -> None:
    rig = Rig()
    sub = rig.null().sub
    assert sub is not None
    assert sub.camera_flags == 0
    assert sub.auto_flip
    assert sub.pip_mode == 0
    rig.command(Osd(True))
    rig.command(OsdCoordinates(OsdCoordinateSource.TARGET))
    rig.command(ImageAutoFlip(False))
    rig.command(TargetDetection(True))
    rig.command(TimeZone(-5))
    sub = rig.command(PictureInPicture(2)).sub
    assert sub is not None
    c = CameraFlags
    on = c.OSD_ON | c.OSD_TARGET_COORDINATES | c.AUTO_FLIP_OFF | c.TARGET_DETECTION_ON
    assert sub.camera_flags == on
    assert not sub.auto_flip
    assert sub.pip_mode == 2
    assert sub.time_zone == -5
    assert sub_of(rig.command(PictureInPicture(0))).pip_mode == 3
    rig.command(PictureInPicture(4))
    assert sub_of(rig.command(PictureInPicture(0))).pip_mode == 1
    rig.command(Osd(False))
    assert not sub_of(rig.null()).camera_flags & CameraFlags.OSD_ON
