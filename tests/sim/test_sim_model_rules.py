"""Sans-I/O SimulatorModel: packet handling, feedback rules, the same-opcode rule, garbage."""

from __future__ import annotations

import struct

import pytest

from gcu_async.protocol import (
    Calibration,
    Command,
    Focus,
    NullCommand,
    Opcode,
    Palette,
    Record,
    TakePhoto,
    ZoomTo,
    crc16_xmodem,
    decode_gcu_packet,
)
from gcu_async.sim import SimulatorModel
from helpers.sim.support import FAMILIES, Rig, host_bytes, sub_of


@pytest.mark.parametrize(("command", "status"), FAMILIES, ids=lambda v: repr(v)[:40])
def test_every_family_gets_its_status(command: Command, status: int) -> None:
    rig = Rig()
    reply = rig.command(command)
    assert reply.feedback.opcode == command.opcode
    assert reply.feedback.status == status


def test_every_family_in_one_sequence() -> None:
    rig = Rig()
    got = [(c.opcode, rig.command(c).feedback.status) for c, _ in FAMILIES]
    assert got == [(c.opcode, s) for c, s in FAMILIES]
    assert rig.model.stats.malformed == 0


def test_null_command_answers_without_status() -> None:
    rig = Rig()
    raw = rig.model.receive(host_bytes(NullCommand()))
    assert len(raw) == 1
    assert len(raw[0]) == 72
    reply = decode_gcu_packet(raw[0])
    assert reply.feedback.opcode == 0
    assert reply.feedback.status is None
    assert not rig.model.executions


def test_same_opcode_executes_once_until_a_null() -> None:
    rig = Rig()
    replies = [rig.send(TakePhoto()) for _ in range(5)]
    assert [(r.feedback.opcode, r.feedback.status) for r in replies] == [(0x20, 0)] * 5
    assert rig.model.executions[Opcode.TAKE_PHOTO] == 1
    assert rig.model.state.camera.photos == {1: 1}
    assert rig.model.stats.repeated == 4
    rig.null()
    rig.send(TakePhoto())
    assert rig.model.executions[Opcode.TAKE_PHOTO] == 2
    assert rig.model.state.camera.photos == {1: 2}


def test_a_different_opcode_also_separates() -> None:
    rig = Rig()
    for command in (TakePhoto(), Focus(), TakePhoto(), Focus()):
        rig.send(command)
    assert rig.model.executions == {Opcode.TAKE_PHOTO: 2, Opcode.FOCUS: 2}


def test_same_opcode_with_other_parameters_is_ignored() -> None:
    rig = Rig()
    rig.send(ZoomTo(ratio=5.0))
    rig.send(ZoomTo(ratio=20.0))  # same opcode: not executed
    rig.run(5.0)
    assert rig.model.state.zoom[1] == pytest.approx(5.0)
    assert rig.model.executions[Opcode.ZOOM_TO] == 1


def test_record_toggles_once_per_execution() -> None:
    rig = Rig()
    for _ in range(3):
        reply = rig.send(Record())
    assert reply.sub is not None
    assert reply.sub.recording
    reply = rig.command(Record())
    assert reply.sub is not None
    assert not reply.sub.recording
    assert rig.model.executions[Opcode.RECORD] == 2


def test_repeated_failure_repeats_the_failure() -> None:
    rig = Rig("Z-6A")
    statuses = [rig.send(Palette(2)).feedback.status for _ in range(3)]
    assert statuses == [0x02, 0x02, 0x02]
    assert rig.model.executions[Opcode.PALETTE] == 1


def test_calibration_in_progress_then_success() -> None:
    rig = Rig()
    assert rig.send(Calibration()).feedback.status == 0x02
    statuses = []
    for _ in range(40):  # keep repeating CALIBRATION for 4 s of clock time
        rig.clock.advance(0.1)
        statuses.append(rig.send(Calibration()).feedback.status)
    assert statuses[:25] == [0x02] * 25  # 0.1 … 2.5 s
    assert statuses[-5:] == [0x00] * 5
    assert rig.model.executions[Opcode.CALIBRATION] == 1
    assert not rig.model.state.calibrating


def test_unknown_subframe_request_gives_all_zero_subframe() -> None:
    rig = Rig()
    for code in (0x00, 0x02, 0x7F, 0xFF):
        raw = rig.model.receive(host_bytes(TakePhoto(), subframe_request=code))[0]
        assert raw[37:69] == bytes(32), code
        rig.null()
    raw = rig.model.receive(host_bytes(subframe_request=0x01))[0]
    assert raw[37] == 0x01
    assert sub_of(decode_gcu_packet(raw)).pod_code == 45


def _with_crc(packet: bytearray) -> bytes:
    packet[-2:] = struct.pack(">H", crc16_xmodem(bytes(packet[:-2])))
    return bytes(packet)


def test_garbage_is_ignored_and_counted() -> None:
    model = SimulatorModel()
    good = host_bytes(TakePhoto())
    replies = model.receive(b"\x00\x01garbage\xa8" + good + b"\xa8\xe5\x48junk")
    assert len(replies) == 1
    assert decode_gcu_packet(replies[0]).feedback.opcode == Opcode.TAKE_PHOTO
    assert model.stats.bytes_discarded >= 10
    assert model.stats.answered == 1


def test_bad_crc_is_not_answered() -> None:
    model = SimulatorModel()
    bad = bytearray(host_bytes(TakePhoto()))
    bad[-1] ^= 0x01
    assert model.receive(bytes(bad)) == []
    assert model.stats.crc_errors == 1
    assert model.stats.answered == 0
    assert not model.executions


def test_out_of_range_parameters_are_answered_with_a_failure() -> None:
    """Liberal receive: ZZ ZZ = 0 lies in neither defined range; the GCU answers every
    CRC-valid packet, so the simulator answers it with the zoom failure status (the named
    cameras) and leaves the zoom alone."""
    model = SimulatorModel()
    zoom = model.state.camera.main_zoom
    packet = bytearray(host_bytes(ZoomTo(ratio=2.0, cameras=3)))
    packet[71:73] = struct.pack("<h", 0)
    [reply] = model.receive(_with_crc(packet))
    feedback = decode_gcu_packet(reply).feedback
    assert (feedback.opcode, feedback.status) == (0x25, 0x03)
    assert (model.stats.anomalous, model.stats.malformed, model.stats.answered) == (1, 0, 1)
    model.advance(model.clock.now() + 5.0)
    assert model.state.camera.main_zoom == zoom


def test_any_chunking_gives_the_same_reply() -> None:
    whole = SimulatorModel().receive(host_bytes(TakePhoto()))
    model = SimulatorModel()
    data = host_bytes(TakePhoto())
    got: list[bytes] = []
    for i in range(len(data)):
        got += model.receive(data[i : i + 1])
        assert (len(got) == 1) == (i == len(data) - 1)
    assert got == whole


def test_unknown_opcode_fails() -> None:
    model = SimulatorModel()
    packet = bytearray(host_bytes())
    packet[69] = 0x42
    reply = decode_gcu_packet(model.receive(_with_crc(packet))[0])
    assert (reply.feedback.opcode, reply.feedback.status) == (0x42, 0x01)


def test_protocol_version_1_is_accepted() -> None:
    model = SimulatorModel()
    reply = decode_gcu_packet(model.receive(host_bytes(TakePhoto(), version=1))[0])
    assert reply.feedback.status == 0
    assert reply.version == 2


def test_invalid_construction_arguments() -> None:
    with pytest.raises(ValueError, match="pod model"):
        SimulatorModel("no-such-pod")
    with pytest.raises(ValueError, match="max_zoom"):
        SimulatorModel(max_zoom=0.5)
    with pytest.raises(ValueError, match="calibration_seconds"):
        SimulatorModel(calibration_seconds=-1)


def test_pod_code_or_name_selects_the_model() -> None:
    assert SimulatorModel(0).profile.name == "Z-6A"
    assert SimulatorModel("d_90ai").profile.model == 41
    sub = decode_gcu_packet(SimulatorModel("Z-6A").receive(host_bytes())[0]).sub
    assert sub is not None
    assert sub.pod_code == 0


def test_simulator_takes_a_model_or_its_settings_not_both() -> None:
    from gcu_async.sim import GcuSimulator

    model = SimulatorModel("Z-6A")
    assert GcuSimulator(model).model is model
    with pytest.raises(ValueError, match="not both"):
        GcuSimulator(model, pod="D-80AI")
