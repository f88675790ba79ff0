"""What the simulator does with host deviations it meets in the field (docs/protocol-notes.md
§14 "Photo, record and focus with parameter byte 0x00", §15 "Aircraft yaw outside [0,
36000)"): photo, record and focus with 0x00 run (flagged), every other anomalous command
does not; an out-of-range aircraft yaw is read as the host meant it; frame-field anomalies
are counted per field and logged once."""

from __future__ import annotations

import logging

import pytest

from gcu_async.protocol import HOST_HEADER, ExecutionStatus, Opcode, decode_gcu_packet
from gcu_async.sim import ManualClock, SimulatorModel
from gcu_async.sim.aircraft import aircraft_yaw
from helpers.protocol.strategies import seal
from helpers.sim.support import host_bytes


def with_command(opcode: int, params: bytes, yaw_raw: int | None = None) -> bytes:
    body = bytearray(host_bytes()[5:69])
    if yaw_raw is not None:
        body[11:13] = yaw_raw.to_bytes(2, "little")  # host bytes 16–17
    return seal(HOST_HEADER, bytes(body) + bytes([opcode]) + params)


NULL = host_bytes()


def run(model: SimulatorModel, *packets: bytes) -> list[int]:
    """Feed each packet with a null between; the execution status of each."""
    statuses = []
    for p in packets:
        [reply] = model.receive(p)
        statuses.append(decode_gcu_packet(reply).feedback.status)
        model.receive(NULL)
    return statuses


def test_record_with_zero_toggles_like_the_document_value() -> None:
    model = SimulatorModel(clock=ManualClock())
    start, stop = with_command(0x21, b"\x01"), with_command(0x21, b"\x00")
    assert run(model, start) == [0]
    assert model.state.camera.recording is True
    assert run(model, stop) == [0]  # ArduPilot's stop
    assert model.state.camera.recording is False
    assert model.stats.anomalous == model.stats.tolerated == 1
    assert model.executions[Opcode.RECORD] == 2


@pytest.mark.parametrize("opcode", [0x20, 0x26])
def test_photo_and_focus_with_zero_run_on_camera_1(opcode: int) -> None:
    model = SimulatorModel(clock=ManualClock())
    assert run(model, with_command(opcode, b"\x00")) == [0]
    cam = model.state.camera
    assert (cam.photos.get(1, 0), cam.focus_count) == ((1, 0) if opcode == 0x20 else (0, 1))
    assert model.stats.tolerated == 1


@pytest.mark.parametrize(
    ("opcode", "params"),
    [(0x21, b"\x01\x00"),  # two parameter bytes
     (0x22, b"\x00"),  # zoom names no camera: not a fixed-0x01 command
     (0x2A, b"\x00\x01")],  # palette without a camera
)  # fmt: skip
def test_other_anomalous_commands_still_fail(opcode: int, params: bytes) -> None:
    model = SimulatorModel(clock=ManualClock())
    [reply] = model.receive(with_command(opcode, params))
    assert decode_gcu_packet(reply).feedback.result is not ExecutionStatus.SUCCESS
    assert model.stats.tolerated == 0 and model.stats.anomalous == 1
    assert not model.state.camera.recording


@pytest.mark.parametrize(
    ("raw", "degrees"),
    [(0, 0.0), (35999, 359.99), (65536 - 11000, 250.0), (65535, 359.99),
     (65536 - 18000, 180.0), (36000, 0.0), (40000, 40.0), (47535, 115.35)],
)  # fmt: skip
def test_aircraft_yaw_reading(raw: int, degrees: float) -> None:
    assert aircraft_yaw(raw) == pytest.approx(degrees)


def test_signed_yaw_is_used_counted_and_logged_once(caplog: pytest.LogCaptureFixture) -> None:
    model = SimulatorModel(clock=ManualClock())
    caplog.set_level(logging.WARNING, "gcu_async.sim")
    for _ in range(3):
        model.receive(with_command(0x00, b"", yaw_raw=65536 - 11000))  # ArduPilot's 250°
    assert model.state.aircraft.attitude.yaw == pytest.approx(250.0)
    assert model.stats.frame_anomalies == 3
    assert model.stats.anomalies_by_field == {"aircraft_yaw_raw": 3}
    warnings = [r.getMessage() for r in caplog.records if "aircraft_yaw_raw" in r.getMessage()]
    assert len(warnings) == 1
    assert "signed ±18000" in warnings[0] and "uses 250.00°" in warnings[0]
    report = model.conformance.report()
    assert report.keys == ("main.aircraft_yaw_raw",)


def test_a_model_that_overrides_handle_with_its_documented_signature_still_works() -> None:
    """Applications watch packets by overriding ``handle(packet)``; the conformance report
    still shows each deviating packet's bytes as they arrived."""
    seen: list[int] = []

    class Watching(SimulatorModel):
        def handle(self, packet):  # type: ignore[no-untyped-def]
            seen.append(packet.version)
            return super().handle(packet)

    model = Watching(clock=ManualClock())
    packet = host_bytes(version=3)
    assert model.receive(packet)  # answered
    assert seen == [3]
    (deviation,) = [d for d in model.conformance.report().deviations if d.examples]
    assert deviation.examples[0].raw_hex.replace(" ", "").lower() == packet.hex()
