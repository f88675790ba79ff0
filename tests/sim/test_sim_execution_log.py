"""The model's execution log: one record per executed command, in order, with its time,
typed command (parameters included) and status; repeats and null commands are not in it."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcu_async.protocol import (
    Calibration,
    Command,
    FillLight,
    NullCommand,
    Opcode,
    Record,
    TakePhoto,
    ZoomTo,
    command_code,
    decode_gcu_packet,
)
from gcu_async.sim import ExecutionRecord, SimulatorModel
from helpers.sim.support import Rig, host_bytes


def test_off_by_default_the_counter_still_counts() -> None:
    rig = Rig()
    rig.command(TakePhoto())
    assert rig.model.record_executions is False
    assert rig.model.execution_log == []
    assert rig.model.executions[Opcode.TAKE_PHOTO] == 1


def test_records_time_command_and_status_and_skips_repeats_and_nulls() -> None:
    rig = Rig(record_executions=True)
    rig.null()
    rig.clock.advance(0.5)
    rig.send(ZoomTo(ratio=10.0))  # t=0.5, executed
    rig.clock.advance(0.1)
    rig.send(ZoomTo(ratio=20.0))  # same opcode right after: not executed
    rig.null()
    rig.clock.advance(0.1)
    rig.send(ZoomTo(ratio=20.0))  # t=0.7, executed (a null came between)
    rig.clock.advance(0.1)
    rig.send(FillLight(64))  # t=0.8, ○ on D-90Pro(TA): executed, fails with 0x01
    rig.clock.advance(0.1)
    rig.send(Calibration())  # t=0.9, 0x02 in progress
    rig.send(Calibration())  # repeat: answered with the progress, not executed
    log = rig.model.execution_log
    assert log == [
        ExecutionRecord(0.5, ZoomTo(ratio=10.0), 0x00),
        ExecutionRecord(pytest.approx(0.7), ZoomTo(ratio=20.0), 0x00),
        ExecutionRecord(pytest.approx(0.8), FillLight(64), 0x01),
        ExecutionRecord(pytest.approx(0.9), Calibration(), 0x02),
    ]
    # two commands of one opcode told apart by their parameters
    assert log[0].command != log[1].command
    assert sum(rig.model.executions.values()) == len(log)


def test_the_flag_must_be_a_bool() -> None:
    with pytest.raises(TypeError, match=r"record_executions: expected a bool .* int 1"):
        SimulatorModel(record_executions=1)  # type: ignore[arg-type]


# A small pool on purpose, so that consecutive equal opcodes (with different parameters)
# are frequent: the same-opcode rule is what the log has to get right.
POOL: list[Command] = [
    NullCommand(),
    TakePhoto(),
    Record(),
    ZoomTo(ratio=5.0),
    ZoomTo(ratio=12.0),
    FillLight(10),
]
STEP = st.tuples(
    st.sampled_from(range(len(POOL))),
    st.sampled_from([0.0, 0.01, 0.25]),  # clock advance before the packet
    st.booleans(),  # corrupt the packet's CRC: rejected, and the rule does not see it
)


@given(st.lists(STEP, max_size=40))
def test_log_matches_a_reference_of_the_same_opcode_rule(
    steps: list[tuple[int, float, bool]],
) -> None:
    rig = Rig(record_executions=True)
    expected: list[tuple[float, Command, int]] = []
    previous: int | None = None
    for index, advance, corrupt in steps:
        command = POOL[index]
        now = rig.clock.advance(advance)
        data = bytearray(host_bytes(command))
        if corrupt:
            data[-1] ^= 0x01
            assert rig.model.receive(bytes(data)) == []
            continue
        replies = rig.model.receive(bytes(data))
        assert len(replies) == 1
        feedback = decode_gcu_packet(replies[0]).feedback
        opcode = command_code(command)
        if opcode != Opcode.NULL and opcode != previous:
            assert feedback.status is not None
            expected.append((now, command, feedback.status))
        previous = opcode
    assert [tuple(r) for r in rig.model.execution_log] == expected
    counted = {op: n for op, n in rig.model.executions.items() if n}
    by_log: dict[int, int] = {}
    for record in rig.model.execution_log:
        by_log[command_code(record.command)] = by_log.get(command_code(record.command), 0) + 1
    assert counted == by_log
