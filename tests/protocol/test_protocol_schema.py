"""The command schema (gcu_async.protocol.commands): every table made from it agrees with it,
every command it lists is covered end to end (codec at the range edges, simulator behaviour,
dissector rows), so a command added to it needs nothing else written in the tests."""

from __future__ import annotations

import copy
import dataclasses
import math
import pickle
import struct
from typing import Any

import pytest

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import commands as c
from gcu_async.protocol import enums, opcodes
from gcu_async.protocol.command_base import Command, codec
from gcu_async.protocol.command_decode import AnomalousCommand, decode_command
from gcu_async.protocol.command_fields import (
    ZOOM_FRACTION,
    ZOOM_RATIO,
    Choice,
    Real,
    Thresholds,
    ZoomValue,
)
from gcu_async.protocol.command_schema import StatusRule
from gcu_async.protocol.commands import COMMAND_TYPES, MODE_COMMANDS
from gcu_async.protocol.feedback import THERMAL_OPCODES, ZOOM_OPCODES
from gcu_async.protocol.fields import WIRE_RANGES, WireField
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
    """helpers.sim.support.FAMILIES (the simulator's command sequence, with the status each
    answers) lists every command: a command added to the schema needs its row there."""
    from helpers.sim.support import FAMILIES

    listed = {type(command) for command, _ in FAMILIES}
    assert listed == set(CLASSES) - {c.NullCommand}, "add it to helpers.sim.support.FAMILIES"


def test_the_simulator_keeps_the_last_accepted_command_of_each_opcode() -> None:
    from gcu_async.protocol.packets import decode_gcu_packet
    from gcu_async.sim import SimulatorModel
    from helpers.sim.support import FAMILIES, host_bytes

    model = SimulatorModel()
    accepted: dict[int, Command] = {}
    for command, _ in FAMILIES:
        (reply,) = model.receive(host_bytes(command))
        if decode_gcu_packet(reply).feedback.status == 0:
            accepted[int(command.OPCODE)] = command
        model.receive(host_bytes())  # the null command: the next may repeat the opcode
    assert model.state.accepted == accepted
    assert accepted  # most do succeed on the default pod


# -- the codec: one check per parameter, in the class, in the order of its fields ----------
def _real_fields(cls: type[Command]) -> list[tuple[str, WireField]]:
    """(the attribute to set, its wire field) of every real parameter a class takes directly:
    a Real, a ZoomValue's ratio or fraction, a threshold (points and boxes: below)."""
    found = []
    for kind in cls.SCHEMA.params:
        if isinstance(kind, Real):
            found.append((kind.field_.name, kind.field_))
        elif isinstance(kind, ZoomValue):
            found += [("ratio", ZOOM_RATIO), ("fraction", ZOOM_FRACTION)]
        elif isinstance(kind, Thresholds):
            found += list(zip(kind.attrs, kind.wire, strict=True))
    return found


REALS = [(cls, attr, w) for cls in CLASSES for attr, w in _real_fields(cls)]


@pytest.mark.parametrize(("cls", "attr", "w"), REALS,
                         ids=[f"{cls.__name__}-{attr}" for cls, attr, _ in REALS])  # fmt: skip
def test_a_real_parameter_is_checked_as_given_not_as_rounded(
    cls: type[Command], attr: str, w: WireField
) -> None:
    """A value less than half a wire step outside the range is refused, as the client's
    methods refuse it, with the range in units; the bounds themselves are taken."""
    low, high = w.raw_low / w.scale, w.raw_high / w.scale
    others: dict[str, object] = {f.name: 0.0 for f in dataclasses.fields(cls)
                                 if f.default is dataclasses.MISSING}  # fmt: skip
    if attr in ("high", "low"):  # the other threshold at its end: only one bound moves
        others = {"low": low} if attr == "high" else {"high": high}
    for bound, outside in ((low, math.nextafter(low, -math.inf)),
                           (high, math.nextafter(high, math.inf))):  # fmt: skip
        assert getattr(cls(**{**others, attr: bound}), attr) == bound
        with pytest.raises(FieldRangeError, match=rf"^{attr}: .* \[{low:.12g}, {high:.12g}\]"):
            cls(**{**others, attr: outside})


@pytest.mark.parametrize("cls", [c.ClickToPan, c.Track], ids=str)
def test_an_image_element_is_checked_as_given(cls: type[Command]) -> None:
    attr = "point" if cls is c.ClickToPan else "box"
    inside = (1.0, 1.0) if attr == "point" else (0.0, 0.0, 1.0, 1.0)
    outside = (math.nextafter(1.0, 2.0), 1.0) if attr == "point" else (
        0.0, 0.0, math.nextafter(1.0, 2.0), 1.0)
    assert cls(**{attr: inside})
    element = "x" if attr == "point" else "right"
    with pytest.raises(FieldRangeError, match=rf"^{attr}\.{element}: "):
        cls(**{attr: outside})


def _bad(kind: Any) -> dict[str, object]:
    """A value of ``kind``'s attributes that it refuses for its type (a zoom value: its
    ratio)."""
    return {"ratio": "bad"} if isinstance(kind, ZoomValue) else dict.fromkeys(kind.attrs, "bad")


MANY = [cls for cls in CLASSES if len(cls.SCHEMA.params) > 1]


@pytest.mark.parametrize("cls", MANY, ids=[cls.__name__ for cls in MANY])
def test_a_command_names_its_first_bad_field_in_field_order(cls: type[Command]) -> None:
    """With every parameter wrong, the error names the class's first field (the order of
    its constructor, which is the client method's), not the first on the wire."""
    bad: dict[str, object] = {}
    for kind in cls.SCHEMA.params:
        bad.update(_bad(kind))
    first = next(f.name for f in dataclasses.fields(cls))
    with pytest.raises(TypeError, match=rf"^{first}\b"):
        cls(**bad)


def test_a_command_keeps_its_parameters_encoded_and_copies_check_again() -> None:
    command = c.GazeAtCoordinates(latitude=38.03, longitude=170.92, altitude=41.123)
    assert command.raw_params() == (1_709_200_000, 380_300_000, 41_123)
    assert command.encode_params() == command.LAYOUT.pack(*command.raw_params())
    for copied in (copy.copy(command), copy.deepcopy(command),
                   pickle.loads(pickle.dumps(command))):  # fmt: skip
        assert copied == command and copied.encode_params() == command.encode_params()
    assert [f.name for f in dataclasses.fields(command)] == ["latitude", "longitude", "altitude"]
    with pytest.raises(FieldRangeError, match=r"^latitude"):
        dataclasses.replace(command, latitude=91.0)
