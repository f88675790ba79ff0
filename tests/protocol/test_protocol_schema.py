"""The command schema (gcu_async.protocol.commands): every table made from it agrees with it,
every command it lists is covered end to end (codec at the range edges, simulator behaviour,
dissector rows), so a command added to it needs nothing else written in the tests."""

from __future__ import annotations

import struct

import pytest

from gcu_async.protocol import commands as c
from gcu_async.protocol import enums, opcodes
from gcu_async.protocol.command_base import Command, codec
from gcu_async.protocol.command_decode import AnomalousCommand, decode_command
from gcu_async.protocol.command_fields import Choice
from gcu_async.protocol.command_schema import StatusRule
from gcu_async.protocol.commands import COMMAND_TYPES, MODE_COMMANDS
from gcu_async.protocol.feedback import THERMAL_OPCODES, ZOOM_OPCODES
from gcu_async.protocol.fields import WIRE_RANGES
from gcu_async.protocol.pods import MATRIX_COMMANDS
from gcu_async.session.control import KIND, MODE_CHANGING, REPORTED
from gcu_async.sim.executor import MODE_OPCODES, handler_for
from gcu_async.wireshark.tables import wire_rows

CLASSES = list(COMMAND_TYPES.values())
IDS = [cls.__name__ for cls in CLASSES]


def test_opcode_lives_below_the_table_and_enums_re_exports_it() -> None:
    assert enums.Opcode is c.Opcode is opcodes.Opcode
    assert enums.opcode_name is opcodes.opcode_name
    with pytest.raises(AttributeError):
        enums.NoSuchThing  # noqa: B018


@pytest.mark.parametrize("cls", [cls for cls in CLASSES if cls is not c.NullCommand], ids=str)
def test_every_command_has_simulator_behaviour(cls: type[Command]) -> None:
    assert handler_for(cls) is not None, f"sim/executor.py: no @behaviour({cls.__name__})"


def test_mode_tables_are_the_schema_s() -> None:
    modes = {cls.OPCODE: cls.SCHEMA.mode for cls in CLASSES if cls.SCHEMA.mode is not None}
    assert set(modes) == MODE_COMMANDS == set(KIND) == set(REPORTED) == set(MODE_OPCODES)
    for opcode, spec in modes.items():
        assert REPORTED[opcode] is spec.mode is MODE_OPCODES[opcode]
        assert KIND[opcode].value == spec.control
    assert MODE_CHANGING >= MODE_COMMANDS
    assert {
        cls.OPCODE for cls in CLASSES if cls.SCHEMA.changes_mode
    } == MODE_CHANGING - MODE_COMMANDS


def test_status_sets_and_support_matrix_are_the_schema_s() -> None:
    assert {cls.OPCODE for cls in CLASSES if cls.SCHEMA.status is StatusRule.ZOOM} == ZOOM_OPCODES
    thermal = {cls.OPCODE for cls in CLASSES if cls.SCHEMA.status is StatusRule.THERMAL}
    assert thermal == THERMAL_OPCODES
    assert len(set(MATRIX_COMMANDS)) == len(MATRIX_COMMANDS)  # one row per opcode
    assert set(MATRIX_COMMANDS) <= set(COMMAND_TYPES) - {c.Opcode.NULL}


def test_wire_rows_list_every_opcode_with_fixed_length_parameters() -> None:
    rows = wire_rows()
    assert [r.opcode for r in rows] == sorted(COMMAND_TYPES)
    for row in rows:
        cls = COMMAND_TYPES[row.opcode]
        assert row.command == cls.OPCODE.name
        fmt = "<" + "".join(p.fmt for p in row.params)
        assert struct.calcsize(fmt) == cls.LAYOUT.size
        assert [p.name for p in row.params] == [w.name for w in cls.SCHEMA.wire]
        for p in row.params:
            own = WIRE_RANGES[p.fmt]
            assert p.low is None or own[0] < p.low <= own[1]
            assert p.high is None or own[0] <= p.high < own[1]
            assert p.enum is None or isinstance(getattr(enums, p.enum, None), type)


def _edge(cls: type[Command], high: bool) -> list[int]:
    return [w.raw_high if high else w.raw_low for w in cls.SCHEMA.wire]


@pytest.mark.parametrize("high", [False, True], ids=["low", "high"])
@pytest.mark.parametrize("cls", CLASSES, ids=IDS)
def test_every_field_at_its_range_edge_round_trips(cls: type[Command], high: bool) -> None:
    params = cls.LAYOUT.pack(*_edge(cls, high))
    command = decode_command(int(cls.OPCODE), params)
    assert type(command) is cls, getattr(command, "anomalies", command)
    assert command.encode_params() == params
    assert type(cls(**{f: getattr(command, f) for f in command.as_dict()["params"]})) is cls


@pytest.mark.parametrize("high", [False, True], ids=["below", "above"])
@pytest.mark.parametrize("cls", CLASSES, ids=IDS)
def test_every_field_just_outside_its_range_is_flagged(cls: type[Command], high: bool) -> None:
    for i, w in enumerate(cls.SCHEMA.wire):
        raw = _edge(cls, high)
        raw[i] = w.raw_high + 1 if high else w.raw_low - 1
        if not WIRE_RANGES[w.fmt][0] <= raw[i] <= WIRE_RANGES[w.fmt][1]:
            continue  # the wire type cannot carry it
        decoded = decode_command(int(cls.OPCODE), cls.LAYOUT.pack(*raw))
        assert isinstance(decoded, AnomalousCommand), (w.name, raw)
        assert w.name in {a.field for a in decoded.anomalies}, (w.name, decoded.anomalies)
        assert decoded.anomalies == cls.raw_anomalies(tuple(raw))


@pytest.mark.parametrize("cls", CLASSES, ids=IDS)
def test_as_dict_writes_each_field_as_its_kind_says(cls: type[Command]) -> None:
    command = decode_command(int(cls.OPCODE), cls.LAYOUT.pack(*_edge(cls, True)))
    params = command.as_dict()["params"]
    for kind in cls.SCHEMA.params:
        for attr in kind.attrs:
            value = getattr(command, attr)
            if isinstance(kind, Choice):
                assert params[attr] == value.name
            elif value is not None:
                assert params[attr] == kind.json(value)


def test_a_schema_that_misses_an_attribute_is_refused() -> None:
    from dataclasses import dataclass

    with pytest.raises(TypeError, match="schema parameters"):

        @codec
        @dataclass(frozen=True, slots=True)
        class Broken(Command):
            OPCODE = c.Opcode.OSD
            enabled: bool = True



def test_every_command_family_runs_on_the_simulator() -> None:
    """tests/_sim_helpers.FAMILIES (the simulator's command sequence, with the status each
    answers) lists every command: a command added to the schema needs its row there."""
    from _sim_helpers import FAMILIES

    listed = {type(command) for command, _ in FAMILIES}
    assert listed == set(CLASSES) - {c.NullCommand}, "add the command to _sim_helpers.FAMILIES"


def test_the_simulator_keeps_the_last_accepted_command_of_each_opcode() -> None:
    from _sim_helpers import FAMILIES, host_bytes
    from gcu_async.protocol.packets import decode_gcu_packet
    from gcu_async.sim import SimulatorModel

    model = SimulatorModel()
    accepted: dict[int, Command] = {}
    for command, _ in FAMILIES:
        (reply,) = model.receive(host_bytes(command))
        if decode_gcu_packet(reply).feedback.status == 0:
            accepted[int(command.OPCODE)] = command
        model.receive(host_bytes())  # the null command: the next may repeat the opcode
    assert model.state.accepted == accepted
    assert accepted  # most do succeed on the default pod
