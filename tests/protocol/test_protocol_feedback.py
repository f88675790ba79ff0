"""Execution status is read per command (docs/protocol-notes.md §2 "Execution status per command"):
calibration 0x02 = in progress, palette/thermal failure 0x02, zoom failure = camera mask, no status
= NONE."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.errors import CommandFailed, GcuError
from gcu_async.protocol import (
    CameraMask,
    ExecutionStatus,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    Opcode,
    decode_gcu_packet,
    failure_status,
    read_status,
)

ZOOM = [Opcode.ZOOM_IN, Opcode.ZOOM_OUT, Opcode.ZOOM_STOP, Opcode.ZOOM_TO]
THERMAL = [
    Opcode.PALETTE,
    Opcode.AREA_TEMPERATURE,
    Opcode.TEMPERATURE_ALARM,
    Opcode.ISOTHERM,
    Opcode.SPOT_TEMPERATURE,
]
OTHER = [op for op in Opcode if op not in ZOOM and op not in THERMAL]


def test_calibration_in_progress_then_done() -> None:
    assert Feedback(Opcode.CALIBRATION, 0x02).result is ExecutionStatus.IN_PROGRESS
    assert Feedback(Opcode.CALIBRATION, 0x00).result is ExecutionStatus.SUCCESS
    assert Feedback(Opcode.CALIBRATION, 0x01).result is ExecutionStatus.FAILED
    assert failure_status(Opcode.CALIBRATION) == 0x01


@pytest.mark.parametrize("op", THERMAL, ids=lambda o: o.name)
def test_palette_and_thermal_failure_is_0x02(op: Opcode) -> None:
    assert failure_status(op) == 0x02
    assert Feedback(op, 0x02).result is ExecutionStatus.FAILED
    assert Feedback(op, 0x00).result is ExecutionStatus.SUCCESS
    assert Feedback(op, 0x02).failed_cameras == CameraMask(0)


@pytest.mark.parametrize("op", ZOOM, ids=lambda o: o.name)
def test_zoom_failure_names_failed_cameras(op: Opcode) -> None:
    fb = Feedback(op, 0x03)
    assert fb.result is ExecutionStatus.FAILED
    assert fb.failed_cameras == CameraMask.CAMERA_1 | CameraMask.CAMERA_2
    assert Feedback(op, 0x80).failed_cameras == CameraMask.CAMERA_8
    assert Feedback(op, 0x00).failed_cameras == CameraMask(0)
    assert Feedback(op, 0x00).result is ExecutionStatus.SUCCESS
    assert failure_status(op, CameraMask.CAMERA_2) == 0x02
    assert failure_status(op) == 0x01


@pytest.mark.parametrize("op", OTHER, ids=lambda o: o.name)
def test_other_commands_fail_with_0x01(op: Opcode) -> None:
    assert failure_status(op) == 0x01
    assert Feedback(op, 0x01).result is ExecutionStatus.FAILED
    assert Feedback(op, 0x01).failed_cameras == CameraMask(0)
    if op != Opcode.CALIBRATION:
        assert Feedback(op, 0x02).result is ExecutionStatus.FAILED


@given(op=st.integers(0, 255), mask=st.integers(1, 255))
def test_failure_status_consistent_with_read_status(op: int, mask: int) -> None:
    status = failure_status(op, mask)
    assert status != 0
    assert read_status(op, status) is ExecutionStatus.FAILED
    assert read_status(op, 0) is ExecutionStatus.SUCCESS
    assert read_status(op, None) is ExecutionStatus.NONE
    fb = Feedback(op, status)
    assert fb.result is ExecutionStatus.FAILED
    assert not fb.succeeded
    assert int(fb.failed_cameras) == (mask if op in ZOOM else 0)


def test_no_status_is_none_and_packet_is_72_bytes() -> None:
    fb = Feedback(Opcode.NULL)
    assert fb.status is None
    assert fb.result is ExecutionStatus.NONE
    assert not fb.succeeded
    wire = GcuPacket(GcuMainFrame(), None, fb).encode()
    assert len(wire) == 72
    assert decode_gcu_packet(wire).feedback == fb


def test_feedback_as_dict() -> None:
    assert Feedback(0x25, 0x02).as_dict() == {
        "command": "ZOOM_TO",
        "opcode": 0x25,
        "status": "FAILED",
        "status_raw": 2,
        "failed_cameras": 2,
    }
    assert Feedback(0x99, None).as_dict()["command"] == "UNKNOWN_0x99"
    assert Feedback(0x01, 0x02).as_dict()["status"] == "IN_PROGRESS"


def test_command_failed_message() -> None:
    err = CommandFailed(0x25, 0x03, CameraMask(0x03), name="ZOOM_TO")
    assert isinstance(err, GcuError)
    assert err.failed_cameras == CameraMask.CAMERA_1 | CameraMask.CAMERA_2
    assert str(err) == "ZOOM_TO (0x25) failed: status 0x03, failed cameras 0x03"
    assert str(CommandFailed(0x2A, 0x02, name="PALETTE")) == "PALETTE (0x2A) failed: status 0x02"
    assert str(CommandFailed(0x03, None, name="CENTRE")) == "CENTRE (0x03) failed: status none"
    # errors.py imports nothing of the package: without a name, the opcode names itself
    assert str(CommandFailed(0x03, None)) == "opcode 0x03 failed: status none"
