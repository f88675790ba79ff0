"""The simulator as ArduPilot SITL's XF gimbal: the real, hardware-tested host driver
(``AP_Mount_XFRobot`` in ArduPilot 4.7) talks to the simulator over TCP, driven by pymavlink
like a ground station (docs/ardupilot-sitl.md).

Runs the ``arducopter`` binary named by the environment variable ``GCU_ARDUPILOT_SITL``
(skipped, with that reason, when it is unset); its ``copter.parm`` is taken from the same
folder when present. One SITL session (about a minute: boot, commands, GPS lock, take-off)
serves every test of this module. ``GCU_SITL_RECORD=FILE`` also writes the conversation in
the format of tests/data/ardupilot-4.7.0-sitl.gcuconv.gz (how that file was made).
"""

from __future__ import annotations

import math
import os
from collections import Counter
from pathlib import Path

import pytest

from gcu_async.conformance import HostConformance
from gcu_async.protocol import AnomalousCommand, Opcode, command_code
from helpers.sitl.ardupilot import (
    ANGLE_TOLERANCE,
    HEADER,
    Session,
    run_session,
    save_conversation,
    wrap180,
)

ENV = "GCU_ARDUPILOT_SITL"
ARDUPILOT_DEVIATIONS = (
    "main.aircraft_yaw_raw",  # signed ±18000 yaw in the U16 field
    "velocity.scale",  # dm/s instead of 0.01 m/s
    "main.all_zero",  # camera-command packets with an all-zero main frame
    "ins_valid.toggles",  # … so INS valid flips
    "opcode.standing.ANGLE_CONTROL",  # 0x10 instead of the null command
    "command.RECORD.cameras",  # record stop with parameter byte 0x00
)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Session:
    binary = os.environ.get(ENV)
    if not binary:
        pytest.skip(f"{ENV} is not set: no ArduPilot SITL binary (arducopter) to run")
    path = Path(binary).resolve()
    if not path.is_file() or not os.access(path, os.X_OK):
        pytest.fail(f"{ENV}={binary!r} is not an executable file")
    pytest.importorskip("pymavlink", reason="pymavlink (the mavlink extra) drives SITL")
    result = run_session(path, tmp_path_factory.mktemp("sitl"))
    record = os.environ.get("GCU_SITL_RECORD")
    if record and result.model is not None:
        save_conversation(Path(record), result.model.conversation, HEADER)
    print(f"\nSITL session: {result.total_s:.1f} s, gimbal heard after {result.boot_s:.1f} s")
    return result


def test_every_packet_is_answered_and_none_is_malformed(session: Session) -> None:
    model = session.model
    assert model is not None
    s = model.stats
    assert s.received > 1500  # ~50/s for the whole session
    assert s.answered == s.received
    assert s.crc_errors == s.malformed == s.length_errors == s.bytes_discarded == 0
    assert all(reply for _, _, reply in model.conversation)
    print(f"\n{s.received} host packets, {s.answered} answered")


@pytest.mark.parametrize("index", range(4))
def test_the_simulator_reaches_the_angle_and_ardupilot_agrees(session: Session,
                                                              index: int) -> None:  # fmt: skip
    check = session.angles[index]
    pitch, yaw = check.target
    assert abs(check.sim[0] - pitch) < ANGLE_TOLERANCE, check
    assert abs(wrap180(check.sim[1] - yaw)) < ANGLE_TOLERANCE, check
    # ArduPilot reads the camera's absolute pitch and the relative Z angle as its yaw
    assert abs(check.ardupilot[0] - check.sim[0]) < ANGLE_TOLERANCE, check
    assert abs(wrap180(check.ardupilot[1] - check.sim_relative_yaw)) < ANGLE_TOLERANCE, check
    print(f"\n{check.how}: target {check.target}, simulator {check.sim[0]:.2f}/"
          f"{check.sim[1]:.2f}, ArduPilot {check.ardupilot[0]:.2f}/{check.ardupilot[1]:.2f}, "
          f"{check.settle_s:.2f} s")  # fmt: skip


def test_earth_frame_yaw_lands_where_asked_despite_the_signed_yaw(session: Session) -> None:
    """ArduPilot sends heading 250° as −110° in the U16 field; read as U16 the simulator's
    absolute yaw would be 64.6° off (docs/protocol-notes.md §15)."""
    earth = next(c for c in session.angles if c.frame == "earth")
    assert abs(wrap180(earth.sim[1] - earth.target[1])) < ANGLE_TOLERANCE
    assert not math.isnan(earth.ardupilot[1])


def test_each_camera_command_ran_once(session: Session) -> None:
    model = session.model
    assert model is not None
    ran = Counter(command_code(r.command) for r in model.execution_log)
    want = {Opcode.TAKE_PHOTO: 2, Opcode.RECORD: 2, Opcode.ZOOM_IN: 1, Opcode.ZOOM_OUT: 1,
            Opcode.ZOOM_STOP: 2, Opcode.FOCUS: 1}  # fmt: skip
    assert {op: ran[op] for op in want} == want
    assert all(r.status == 0 for r in model.execution_log)
    stop = [r.command for r in model.execution_log if command_code(r.command) == Opcode.RECORD]
    assert isinstance(stop[1], AnomalousCommand) and stop[1].params == b"\x00"
    assert model.stats.tolerated == 1
    assert session.photos == 2 and session.focus == 1
    assert session.recording_after_start is True
    assert session.recording_after_stop is False  # ArduPilot's stop (0x00) stopped it
    assert any("recording OFF" in t for t in session.texts)
    assert not any("failed" in t for t in session.texts)
    z = session.zoom
    assert z["in"] > z["start"] + 1 and z["stop_in"] - z["in"] < 0.5
    assert z["out"] < z["stop_in"] - 1 and z["after_stop"] == z["stop_out"]


def test_the_conformance_report_names_ardupilots_deviations(session: Session) -> None:
    model = session.model
    assert model is not None
    assert session.armed and session.climb_m > 3  # motion, for the velocity check
    report = model.conformance.report()
    print("\n" + report.text())
    assert set(ARDUPILOT_DEVIATIONS) <= set(report.keys)
    diagnosis = {d.key: d.diagnosis for d in report.deviations}
    assert "signed ±18000" in diagnosis["main.aircraft_yaw_raw"]
    assert "(dm/s)" in diagnosis["velocity.scale"]
    assert "never sends the null command" in diagnosis["opcode.standing.ANGLE_CONTROL"]
    assert "0x00 stop" in diagnosis["command.RECORD.cameras"]
    # and the same report again from the raw bytes alone, on the packets' own times
    again = HostConformance()
    for t, packet, _ in model.conversation:
        again.add(packet, t)
    assert again.report().keys == report.keys
