"""Firmware behaviours of the simulator (docs/simulator.md, "Firmware behaviours"): the
table, ``z1pro-6.7`` against the Z-1Pro's logged values, and that a firmware changes how
the replies are filled, never what they mean."""

from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import AngleControl, Centre, FaultFlags, GcuPacket, HostSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.sim import (
    DEFAULT_FIRMWARE,
    FIRMWARES,
    Firmware,
    GcuSimulator,
    SimulatorModel,
    firmware_for,
)
from helpers.protocol import z1pro
from helpers.sim.support import Rig, sub_of


def turned(rig: Rig, yaw: float, seconds: float = 3.0) -> GcuPacket:
    """Angle control to ``yaw`` relative to the (level, north-facing) aircraft, held."""
    rig.control = ControlValues.angles(0.0, 0.0, yaw)
    rig.command(AngleControl())
    return rig.run(seconds)


def test_the_table() -> None:
    assert DEFAULT_FIRMWARE == "v2.0.6"
    assert set(FIRMWARES) >= {"v2.0.6", "z1pro-6.7"}
    for name, firmware in FIRMWARES.items():
        assert firmware.name == name and firmware.summary and firmware.evidence
    document = FIRMWARES[DEFAULT_FIRMWARE]
    assert document == Firmware(DEFAULT_FIRMWARE, document.summary, document.evidence)
    assert document.deviations == frozenset()
    assert FIRMWARES["z1pro-6.7"].deviations == {"yaw_raw"}


def test_firmware_names_are_checked() -> None:
    assert firmware_for("z1pro-6.7") is FIRMWARES["z1pro-6.7"]
    custom = Firmware("mine", "a test", "none", signed_yaw=True)
    assert firmware_for(custom) is custom
    with pytest.raises(ValueError, match=r"firmware: 'z1pro' is not one of v2\.0\.6, z1pro-6\.7"):
        SimulatorModel(firmware="z1pro")
    with pytest.raises(TypeError, match="firmware: expected a Firmware"):
        SimulatorModel(firmware=6.7)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="pod=/firmware="):
        GcuSimulator(SimulatorModel(), firmware="z1pro-6.7")


def test_z1pro_sends_the_logged_values() -> None:
    rig = Rig("Z-1Pro", firmware="z1pro-6.7")
    rig.attitude = None  # the logged host sent no aircraft data
    reply = turned(rig, -140.0)
    sub = sub_of(reply)
    assert reply.version == z1pro.VERSION
    for name in ("hardware_version_raw", "firmware_version_raw", "pod_code", "fault_raw",
                 "camera1_zoom_raw", "camera2_zoom_raw", "thermal_flags_raw",
                 "target_distance_raw"):  # fmt: skip
        assert getattr(sub, name) == z1pro.SUB[name], name
    assert reply.main.mode_raw == z1pro.MAIN["mode_raw"]
    assert reply.main.yaw_raw == 51536  # −140.00° as a signed S16
    assert reply.main.attitude.yaw == 220.0
    assert [a.field for a in reply.anomalies] == ["yaw_raw"]
    assert len(rig.model.receive(_host_null())[0]) == 72  # the null command: no status


def _host_null() -> bytes:
    from helpers.sim.support import host_bytes

    return host_bytes()


def test_the_document_sends_u16_and_the_profile_versions() -> None:
    rig = Rig("Z-1Pro")
    reply = turned(rig, -140.0)
    assert reply.main.yaw_raw == 22000 and reply.main.attitude.yaw == 220.0
    assert reply.anomalies == ()
    sub = sub_of(reply)
    assert sub.camera2_zoom_raw == 0  # no camera 2
    assert (sub.hardware_version, sub.firmware_version) == (
        rig.model.profile.hardware_version, rig.model.profile.firmware_version)
    assert sub.fault_raw == 0


def test_z1pro_gnss_fault_clears_with_satellites() -> None:
    rig = Rig("Z-1Pro", firmware="z1pro-6.7")
    assert sub_of(rig.null()).faults == FaultFlags.GNSS_NO_FIX
    rig.sub = HostSubFrame.build(latitude=38.0, longitude=117.0, altitude=50.0, satellites=12)
    assert sub_of(rig.null()).faults == FaultFlags(0)
    rig.sub = HostSubFrame.build(latitude=38.0, longitude=117.0, altitude=50.0, satellites=0)
    assert sub_of(rig.null()).faults == FaultFlags.GNSS_NO_FIX


def test_centre_in_angle_control_like_the_logged_z1pro() -> None:
    """The Z-1Pro answered centre 0x00 in angle-control mode and stayed at −15° relative yaw;
    the document's simulator refuses it there (0x01). Neither moves."""
    for name, status in ((DEFAULT_FIRMWARE, 0x01), ("z1pro-6.7", 0x00)):
        rig = Rig("Z-1Pro", firmware=name)
        turned(rig, -15.0)
        rig.control = None
        assert rig.command(Centre()).feedback.status == status, name
        assert rig.run(2.0).main.relative_angles.z == pytest.approx(-15.0, abs=0.05), name


def test_the_firmware_can_change_while_the_model_runs() -> None:
    rig = Rig("Z-1Pro")
    reply = turned(rig, -140.0)
    assert reply.main.yaw_raw == 22000
    rig.model.firmware = "z1pro-6.7"
    assert rig.model.firmware is FIRMWARES["z1pro-6.7"]
    assert rig.null().main.yaw_raw == 51536
    assert "firmware=z1pro-6.7" in repr(rig.model)
    with pytest.raises(ValueError, match="is not one of"):
        rig.model.firmware = "z1pro-9"


@given(yaw=st.floats(-180.0, 179.99), pitch=st.floats(-90.0, 30.0),
       aircraft_yaw=st.floats(0.0, 359.99))  # fmt: skip
def test_a_firmware_changes_the_encoding_not_the_meaning(yaw: float, pitch: float,
                                                         aircraft_yaw: float) -> None:  # fmt: skip
    """The same host packets to both firmwares: the same decoded angles; the camera yaw on
    the wire differs exactly by the encoding (U16 vs signed S16)."""
    rigs = [Rig("Z-1Pro", firmware=name) for name in (DEFAULT_FIRMWARE, "z1pro-6.7")]
    replies = []
    for rig in rigs:
        rig.attitude = (0.0, 0.0, aircraft_yaw)
        rig.control = ControlValues.angles(0.0, pitch, yaw)
        rig.command(AngleControl())
        replies.append(rig.run(1.0))
    document, z1pro_frame = (r.main for r in replies)
    assert document.attitude == z1pro_frame.attitude
    assert document.relative_angles == z1pro_frame.relative_angles
    assert 0.0 <= z1pro_frame.attitude.yaw < 360.0
    assert document.yaw_raw < 36000
    signed = z1pro_frame.yaw_raw - 65536 if z1pro_frame.yaw_raw >= 32768 else z1pro_frame.yaw_raw
    assert -18000 <= signed < 18000
    assert signed % 36000 == document.yaw_raw
    assert document._replace(yaw_raw=0) == z1pro_frame._replace(yaw_raw=0)


@pytest.mark.subprocess
def test_sim_cli_plays_the_firmware_and_refuses_unknown_ones() -> None:
    bad = subprocess.run([sys.executable, "-m", "gcu_async", "sim", "--firmware", "z9"],
                         capture_output=True, text=True, timeout=60)  # fmt: skip
    assert bad.returncode == 2
    assert len(bad.stderr.strip().splitlines()) == 1
    assert "invalid choice: 'z9'" in bad.stderr and "z1pro-6.7" in bad.stderr
    help_text = subprocess.run([sys.executable, "-m", "gcu_async", "sim", "--help"],
                               capture_output=True, text=True, timeout=60).stdout  # fmt: skip
    for firmware in FIRMWARES.values():
        assert firmware.name in help_text
