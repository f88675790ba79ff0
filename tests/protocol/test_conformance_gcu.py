"""The GCU conformance report (gcu_async.conformance): each check on GCUs built to break
exactly one rule — the Z-1Pro's signed yaw from its logged values, an emulator that leaves
the absolute yaw zero and answers 73 bytes to everything, a mode byte that never follows,
commands without feedback — the simulator playing the document, which breaks none, and
bounded memory whatever the replies."""

from __future__ import annotations

import json
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.conformance import EXAMPLES, FEEDBACK_GRACE_S, MODE_SETTLE_S, GcuConformance
from gcu_async.protocol import (
    AngleControl,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    Mode,
    Opcode,
    PointingLock,
    TakePhoto,
)
from gcu_async.protocol.host_frame_tables import ControlValues
from helpers.protocol import z1pro
from helpers.protocol.strategies import frames
from helpers.scale import scaled
from helpers.sim.support import Rig

HZ = 50.0


def z1pro_session() -> GcuConformance:
    """The logged moves as replies 0.5 s apart (no host packets)."""
    c = GcuConformance()
    t = 0.0
    for rel0, yaw0, rel1, yaw1 in z1pro.MOVES:
        for rel, yaw in ((rel0, yaw0), (rel1, yaw1)):
            c.add(z1pro.reply(rel, yaw), t)
            t += 0.5
    return c


def test_the_z1pro_signed_yaw_is_named_once_with_its_spread() -> None:
    report = z1pro_session().report()
    assert report.keys == ("main.yaw_raw.signed",)
    d = report.get("main.yaw_raw.signed")
    assert d is not None and d.total == report.replies == 48
    assert d.count == sum((y >= 47536) for m in z1pro.MOVES for y in (m[1], m[3]))
    assert "no camera yaw in the U16-only band 18000…35999" in d.diagnosis
    assert "18000-35999: 0" in d.diagnosis and "47536-65535" in d.diagnosis
    assert 0 < len(d.examples) <= EXAMPLES
    assert all(e.raw_hex.startswith("8a 5e 48 00") and "S16 -" in e.decoded for e in d.examples)
    assert report.identity == {
        "pod_model": "Z-1Pro", "pod_code": 49, "hardware_version": 0.1,
        "hardware_version_raw": 1, "firmware_version": 6.7, "firmware_version_raw": 67,
        "version": 2, "changes": 0,
    }  # fmt: skip
    text = report.text()
    assert "pod: Z-1Pro (code 49), hardware 0.1, firmware 6.7, protocol version 2" in text
    assert "fault bits seen 0x4000" in text and "pod status bits seen 0x1000" in text
    json.dumps(report.as_dict(), allow_nan=False)


def test_the_simulator_playing_the_document_conforms() -> None:
    """A session with a mode command, a command, moves and replies to each packet."""
    rig = Rig("Z-1Pro")
    c = GcuConformance()
    t = 0.0

    def send(command: Any = None) -> None:
        nonlocal t
        raw = rig.model.receive(_host(command, rig.control))[0]
        c.host_sent(Opcode.NULL if command is None else int(command.OPCODE), t)
        c.add(raw, t + 0.002)
        rig.clock.advance(1 / HZ)
        t += 1 / HZ

    for yaw in (-140.0, 60.0, 170.0):
        rig.control = ControlValues.angles(0.0, -10.0, yaw)
        send()
        send(AngleControl())
        for _ in range(int(3 * HZ)):
            send()
    send(TakePhoto())
    for _ in range(5):
        send()
    report = c.report()
    assert report.deviations == (), report.text()
    assert report.host_packets == report.replies
    assert report.latency["count"] == 4 and report.latency["max_ms"] == 2.0
    assert "\n  no deviation found\n" in report.text()


def _host(command: Any, control: ControlValues | None) -> bytes:
    from helpers.sim.support import host_bytes

    return host_bytes(command, control=control, attitude=None)


def emulator_reply(relative_z_raw: int, opcode: int) -> bytes:
    """What the ArduPilot project's XF Robot emulator answers: mode 0x10 always, relative
    angles filled, absolute yaw and the rates left zero, a status byte in every reply."""
    main = GcuMainFrame(mode_raw=Mode.ANGLE_CONTROL, relative_z_raw=relative_z_raw)
    return GcuPacket(main, GcuSubFrame(), Feedback(opcode, 0)).encode()


def test_an_absolute_yaw_left_zero_while_the_relative_yaw_moves() -> None:
    c = GcuConformance()
    for i in range(100):
        c.add(emulator_reply(i * 50, Opcode.NULL), i / HZ)  # relative yaw 0 → 49.5°
    report = c.report()
    d = report.get("main.yaw_raw.zero")
    assert d is not None, report.text()
    assert "moved 49.50°" in d.title
    assert report.get("main.pitch_raw.zero") is None  # relative X never moved
    assert "replies to the null command: 0 of 72 bytes (no status), 100 with a status byte" in (
        report.text())  # fmt: skip
    still = GcuConformance()
    for i in range(100):
        still.add(emulator_reply(0, Opcode.NULL), i / HZ)
    assert still.report().deviations == ()


def mode_session(follows: bool) -> GcuConformance:
    """The host enters pointing lock; the GCU confirms it; its mode byte follows or not."""
    c = GcuConformance()
    t = 0.0
    for i in range(int(2 * MODE_SETTLE_S * HZ)):
        opcode = Opcode.POINTING_LOCK if i in (1, 2) else Opcode.NULL
        c.host_sent(opcode, t)
        mode = Mode.POINTING_LOCK if follows and i >= 5 else Mode.ANGLE_CONTROL
        status = 0 if opcode else None
        c.add_reply(GcuMainFrame(mode_raw=mode), GcuSubFrame(), Feedback(opcode, status),
                    t + 0.001)  # fmt: skip
        t += 1 / HZ
    return c


def test_the_mode_byte_must_follow_a_confirmed_mode_command() -> None:
    stuck = mode_session(follows=False).report()
    assert stuck.keys == ("mode.not_followed",)
    d = stuck.get("mode.not_followed")
    assert d is not None and d.count == 1
    assert "0x11 POINTING_LOCK confirmed, mode byte still 0x10" in d.examples[0].decoded
    followed = mode_session(follows=True).report()
    assert followed.deviations == ()
    assert "mode byte took a confirmed mode within 80 ms" in followed.text()
    assert PointingLock.OPCODE == Opcode.POINTING_LOCK


def test_feedback_timing_missing_and_unsolicited_feedback() -> None:
    c = GcuConformance()
    t = 0.0
    # a photo answered 40 ms after its first packet (two packets of the run)
    for i, fb in enumerate((0, Opcode.TAKE_PHOTO, Opcode.TAKE_PHOTO)):
        c.host_sent(Opcode.TAKE_PHOTO if i < 2 else Opcode.NULL, t)
        c.add_reply(GcuMainFrame(), None, Feedback(fb, 0 if fb else None), t + 0.02)
        t += 0.02
    # zoom in: never answered
    for _ in range(3):
        c.host_sent(Opcode.ZOOM_IN, t)
        c.add_reply(GcuMainFrame(), None, Feedback(0), t + 0.001)
        t += 0.02
    for _ in range(int((FEEDBACK_GRACE_S + 0.5) * HZ)):
        c.host_sent(Opcode.NULL, t)
        c.add_reply(GcuMainFrame(), None, Feedback(0), t + 0.001)
        t += 1 / HZ
    # feedback for a command never sent, and a command answered without a status byte
    c.host_sent(Opcode.RECORD, t)
    c.add_reply(GcuMainFrame(), None, Feedback(Opcode.FOCUS, 0), t + 0.001)
    c.add_reply(GcuMainFrame(), None, Feedback(Opcode.RECORD), t + 0.002)
    report = c.report()
    assert set(report.keys) == {"feedback.missing", "feedback.unsolicited",
                                "feedback.no_status"}, report.text()  # fmt: skip
    missing = report.get("feedback.missing")
    assert missing is not None and missing.count == 1
    assert "0x22 ZOOM_IN in 3 packet(s)" in missing.examples[0].decoded
    assert report.latency["count"] == 2  # the photo, and the record (no status, answered)
    assert report.latency["min_ms"] == 2.0 and report.latency["max_ms"] == 40.0
    assert "while a command stood in consecutive host packets, 2 of" in report.text()


def test_an_opcode_again_after_null_packets_is_seen() -> None:
    c = GcuConformance()
    for i, opcode in enumerate((0x20, 0x20, 0, 0, 0x20, 0)):
        c.host_sent(opcode, i / HZ)
        c.add_reply(GcuMainFrame(), None, Feedback(opcode, 0 if opcode else None),
                    i / HZ + 0.001)  # fmt: skip
    text = c.report().text()
    assert "an opcode sent again after null packets: 1 times, answered 1" in text


def test_without_times_nothing_is_timed() -> None:
    c = GcuConformance()
    c.host_sent(Opcode.TAKE_PHOTO)
    c.add(z1pro.reply(0, 51552, opcode=Opcode.TAKE_PHOTO, status=0))
    report = c.report()
    assert report.duration is None and report.rate == 0.0
    assert "no times given: feedback latency not measured" in report.text()
    d = report.get("main.yaw_raw.signed")
    assert d is not None and "t=" not in report.text()
    assert report.as_dict()["deviations"][0]["examples"][0]["time_s"] is None
    json.dumps(report.as_dict(), allow_nan=False)


def test_undecodable_bytes_are_counted() -> None:
    c = GcuConformance()
    good = z1pro.reply(0, 0)
    c.add(good[:-1] + bytes([good[-1] ^ 1]), 0.0)
    c.add(good, 0.1)
    assert c.report().undecodable == 1 and c.report().replies == 1


@settings(suppress_health_check=[HealthCheck.too_slow], max_examples=scaled(50, 25))
@given(st.lists(st.tuples(frames(GcuMainFrame), st.integers(0, 255),
                          st.one_of(st.none(), st.integers(0, 255))), max_size=60))  # fmt: skip
def test_any_reply_stream_reports_in_bounded_memory(replies: list[Any]) -> None:
    c = GcuConformance(examples=2)
    for i, (main, opcode, status) in enumerate(replies):
        c.host_sent(opcode, i / HZ)
        c.add_reply(main, None, Feedback(opcode, status), i / HZ)
    report = c.report()
    assert all(len(d.examples) <= 2 for d in report.deviations)
    json.dumps(report.as_dict(), allow_nan=False)
    report.text()


def test_memory_stays_bounded_over_many_distinct_anomalies() -> None:
    c = GcuConformance()
    for i in range(20_000):
        c.add_reply(GcuMainFrame(yaw_raw=47536 + i % 18000, miss_x=1001 + i % 30000),
                    GcuSubFrame(pod_code=i % 256), Feedback(0x20 + i % 3, i % 256),
                    i / HZ)  # fmt: skip
    report = c.report()
    assert len(report.deviations) <= 20
    assert all(len(d.examples) <= EXAMPLES for d in report.deviations)
