"""A recorded ArduPilot conversation replayed into the simulator: no SITL needed.

tests/data/ardupilot-4.7.0-sitl.gcuconv.gz holds both directions of a session between
ArduPilot SITL 4.7.0 (its ``AP_Mount_XFRobot`` driver, the hardware-tested host) and the
simulator (made by tests/sitl/test_sitl_ardupilot.py with ``GCU_SITL_RECORD``): ~50 s, 2,400
host packets. Replayed on a :class:`ManualClock` at the recorded times, the simulator must
answer every packet, run each camera command once (record stop with parameter 0x00
included: docs/protocol-notes.md §14), point the camera where the recorded replies — the ones
ArduPilot accepted — say (the aircraft yaw read as ArduPilot meant it: §15), and the
conformance report must name ArduPilot's deviations.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import pytest

from gcu_async.protocol import Opcode, command_code, decode_gcu_packet
from gcu_async.sim import ManualClock, SimulatorModel
from helpers.sitl.ardupilot import load_conversation, wrap180
from test_sitl_ardupilot import ARDUPILOT_DEVIATIONS

DATA = Path(__file__).parent.parent / "data" / "ardupilot-4.7.0-sitl.gcuconv.gz"
TOLERANCE_CENTIDEG = 5
"""0.05°: the replay runs the recorded packets at the recorded times."""


@pytest.fixture(scope="module")
def replay() -> tuple[SimulatorModel, list[tuple[float, bytes, bytes]], list[bytes]]:
    rows = load_conversation(DATA)
    clock = ManualClock()
    model = SimulatorModel(clock=clock, record_executions=True)
    replies = []
    for t, host, _ in rows:
        clock.advance(t - clock.now())
        [reply] = model.receive(host)
        replies.append(reply)
    return model, rows, replies


def test_the_recording_is_a_real_session() -> None:
    rows = load_conversation(DATA)
    assert len(rows) > 2000
    assert rows[-1][0] > 40  # seconds
    assert DATA.stat().st_size < 500_000


def test_every_packet_is_answered(replay: tuple) -> None:
    model, rows, replies = replay
    assert model.stats.answered == len(rows) == len(replies)
    assert model.stats.crc_errors == model.stats.malformed == 0


def test_each_command_runs_once_and_record_stops(replay: tuple) -> None:
    model, _, _ = replay
    ran = Counter(command_code(r.command) for r in model.execution_log)
    want = {Opcode.TAKE_PHOTO: 2, Opcode.RECORD: 2, Opcode.ZOOM_IN: 1, Opcode.ZOOM_OUT: 1,
            Opcode.ZOOM_STOP: 2, Opcode.FOCUS: 1}  # fmt: skip
    assert {op: ran[op] for op in want} == want
    assert all(r.status == 0 for r in model.execution_log)
    assert model.state.camera.recording is False
    assert model.stats.tolerated == 1


def test_the_camera_points_where_the_recorded_replies_say(replay: tuple) -> None:
    """Relative Z, absolute pitch and absolute yaw of every reply against the recorded one
    (ArduPilot's GIMBAL_DEVICE_ATTITUDE_STATUS agreed with those live)."""
    _, rows, replies = replay
    worst = [0, 0, 0]
    for (_, _, recorded), reply in zip(rows, replies, strict=True):
        a, b = decode_gcu_packet(recorded).main, decode_gcu_packet(reply).main
        worst[0] = max(worst[0], abs(a.relative_z_raw - b.relative_z_raw))
        worst[1] = max(worst[1], abs(a.pitch_raw - b.pitch_raw))
        worst[2] = max(worst[2], abs(wrap180((a.yaw_raw - b.yaw_raw) / 100)) * 100)
    assert max(worst) <= TOLERANCE_CENTIDEG, worst


def test_the_conformance_report_names_ardupilots_deviations(replay: tuple) -> None:
    model, _, _ = replay
    report = model.conformance.report()
    assert set(ARDUPILOT_DEVIATIONS) <= set(report.keys), report.text()
    yaw = report.get("main.aircraft_yaw_raw")
    assert yaw is not None and "signed ±18000" in yaw.diagnosis
    velocity = report.get("velocity.scale")
    assert velocity is not None and "(dm/s)" in velocity.diagnosis
    standing = report.get("opcode.standing.ANGLE_CONTROL")
    assert standing is not None and "never sends the null command" in standing.diagnosis
    assert report.as_dict()["conforms"] is False
