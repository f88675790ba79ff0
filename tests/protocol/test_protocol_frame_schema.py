"""The frame schemas: layout, documented byte positions and the generated fast paths.

Each frame's fields are written once, in a :class:`FrameSchema`; the struct, the offsets,
the generated classes (``validate``, ``anomalies``, the unit views, ``as_dict``) and the
packet slices derive from it. These tests hold the derivations to the document (byte
positions) and the generated fast paths to the schema's field-by-field checks they shortcut
(tests/protocol/test_protocol_frame_code.py holds the generated code to the tables).
"""

from __future__ import annotations

import ast
import inspect
import itertools
import re
import struct
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gcu_async.errors import FieldRangeError
from gcu_async.protocol import (
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    decode_gcu_packet,
)
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.frame_schema import FrameSchema, Value
from helpers.protocol.strategies import FRAME_SCHEMAS
from helpers.scale import scaled

SPANS = {HostMainFrame: (5, 36), HostSubFrame: (38, 68), GcuMainFrame: (5, 36),
         GcuSubFrame: (38, 68)}  # fmt: skip
"""The document's byte span of each frame's data (the sub frame's header is byte 37)."""
_BYTES = re.compile(r"^Bytes? (\d+)(?:[–-](\d+))?")


def _documented_bytes(cls: type[Any]) -> dict[str, tuple[int, int]]:
    """Each field's byte span as its docstring in the class states it (``Bytes 8–9, …``)."""
    tree = ast.parse(inspect.getsource(cls))
    body = tree.body[0].body  # type: ignore[attr-defined]
    found: dict[str, tuple[int, int]] = {}
    for node, after in itertools.pairwise(body):
        if isinstance(node, ast.AnnAssign) and isinstance(after, ast.Expr):
            doc = after.value.value  # type: ignore[attr-defined]
            match = _BYTES.match(doc)
            assert match, f"{cls.__name__}.{node.target.id}: no byte position in {doc!r}"  # type: ignore[attr-defined]
            first = int(match[1])
            found[node.target.id] = (first, int(match[2] or first))  # type: ignore[attr-defined]
    return found


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
def test_struct_spans_the_documented_bytes(cls: type[Any]) -> None:
    schema = FRAME_SCHEMAS[cls]
    first, last = SPANS[cls]
    assert (schema.start, schema.end - 1, schema.struct.size) == (first, last, last - first + 1)


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
def test_offsets_are_the_documented_byte_positions(cls: type[Any]) -> None:
    schema = FRAME_SCHEMAS[cls]
    derived = {f.name: (schema.offsets[f.name], schema.offsets[f.name] + f.size - 1)
               for f in schema.fields}  # fmt: skip
    assert derived == _documented_bytes(cls)


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
def test_each_field_lands_at_its_offset_on_the_wire(cls: type[Any]) -> None:
    """Encode a frame whose every field holds a distinct value; read each field back from the
    wire bytes at its offset with int.from_bytes (independently of struct)."""
    schema = FRAME_SCHEMAS[cls]
    values = _distinct(schema)
    frame = cls(**values)
    wire = {HostMainFrame: lambda: HostPacket(frame).encode(),
            HostSubFrame: lambda: HostPacket(HostMainFrame(), frame).encode(),
            GcuMainFrame: lambda: GcuPacket(frame).encode(),
            GcuSubFrame: lambda: GcuPacket(GcuMainFrame(), frame).encode()}[cls]()  # fmt: skip
    for f in schema.fields:
        at = schema.offsets[f.name]
        raw = int.from_bytes(wire[at : at + f.size], "little", signed=f.fmt.islower())
        assert raw == values[f.name], f.name
    used = sum(f.size for f in schema.fields)
    assert wire[schema.start + used : schema.end] == bytes(schema.size - used)  # reserved


def _distinct(schema: FrameSchema) -> dict[str, int]:
    """A value for every field, each distinct and in range (flags: their highest member)."""
    values = {}
    for i, f in enumerate(schema.fields):
        flags = schema.flags.get(f.name)
        values[f.name] = max(int(m) for m in flags) if flags else (f.raw_high - i) or f.raw_low
    return values


def _raw_values(schema: FrameSchema) -> st.SearchStrategy[list[Any]]:
    """Field values around and beyond each range, and of the wrong types."""
    def one(f: WireField) -> st.SearchStrategy[Any]:
        edges = [f.raw_low - 1, f.raw_low, f.raw_high, f.raw_high + 1, 0, 2**40]
        return st.one_of(st.sampled_from(edges), st.integers(f.raw_low - 9, f.raw_high + 9),
                         st.sampled_from([True, 1.0, None, "1"]))  # fmt: skip
    return st.tuples(*(one(f) for f in schema.fields)).map(list)


def _outcome(call: Any) -> Any:
    try:
        return ("ok", call())
    except (TypeError, ValueError) as exc:
        return (type(exc), str(exc))


class _Fallback(Exception):
    """Raised by the schema's field-by-field check where a test forbids the fallback."""


def _no_fallback(self: FrameSchema, frame: Any) -> None:
    raise _Fallback


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
@settings(max_examples=scaled(400, 40), deadline=None)
@given(data=st.data())
def test_generated_validate_is_the_field_by_field_check(cls: type[Any], data: Any) -> None:
    """A frame's generated ``validate`` gives the outcome of the schema's field-by-field
    check, and falls back to it exactly for the frames it refuses."""
    schema = FRAME_SCHEMAS[cls]
    frame = cls(*data.draw(_raw_values(schema)))
    slow = _outcome(lambda: schema.validate(frame))
    assert _outcome(frame.validate) == slow
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(FrameSchema, "validate", _no_fallback)
        assert _passes(frame.validate) == (slow[0] == "ok")


def _passes(call: Any) -> bool:
    try:
        call()
    except _Fallback:
        return False
    return True


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
@settings(max_examples=scaled(400, 40), deadline=None)
@given(data=st.data())
def test_generated_anomalies_are_the_field_by_field_ones(cls: type[Any], data: Any) -> None:
    """Likewise ``anomalies``: the schema's list, and its fallback only for a frame with one."""
    schema = FRAME_SCHEMAS[cls]
    values = [v if type(v) is int else 0 for v in data.draw(_raw_values(schema))]
    frame = cls(*values)
    slow = schema.anomalies(frame)
    assert frame.anomalies == slow
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(FrameSchema, "anomalies", _no_fallback)
        assert _passes(lambda: frame.anomalies) == (slow == ())


def test_a_schema_refuses_what_it_cannot_lay_out() -> None:
    with pytest.raises(ValueError, match="more than the frame's"):
        FrameSchema("Big", "big", 5, 3, (WireField("a", "i"),))
    with pytest.raises(ValueError, match="name no field"):
        FrameSchema("T", "test frame", 5, 4, (WireField("a", "h"),),
                    (Value(name="b", fields=("b",)),))  # fmt: skip
    with pytest.raises(ValueError, match="duplicate"):
        FrameSchema("T", "test frame", 5, 4, (WireField("a", "h"), WireField("a", "h")))


@pytest.mark.parametrize("cls", list(FRAME_SCHEMAS), ids=lambda c: c.__name__)
def test_every_field_reaches_as_dict_raw(cls: type[Any]) -> None:
    """Each raw field of a frame whose every field holds a distinct value appears in its
    ``as_dict``: under its own name or in a view's ``*_raw`` list, at its place."""
    schema = FRAME_SCHEMAS[cls]
    frame = cls(**_distinct(schema))
    shown = frame.as_dict()
    for i, f in enumerate(schema.fields):
        lists = [v for k, v in shown.items() if k.endswith("_raw") and isinstance(v, list)]
        assert shown.get(f.name) == frame[i] or any(frame[i] in v for v in lists), f.name


def test_decode_takes_the_fields_from_the_schema_slices() -> None:
    """A packet whose every main/sub field is distinct decodes each into its own field."""
    main = GcuMainFrame(*range(1, 14))
    sub = GcuSubFrame(*range(21, 34))
    assert decode_gcu_packet(GcuPacket(main, sub).encode()) == GcuPacket(main, sub)
    assert struct.calcsize("<" + FRAME_SCHEMAS[GcuMainFrame].format) == 32


def test_a_reply_lists_its_sub_frame_anomalies() -> None:
    """GcuPacket.anomalies includes the sub frame's (in wire order: version, main, sub,
    feedback): a ranged target longitude past 180° is kept and flagged on receive, and
    refused on send."""
    field = FRAME_SCHEMAS[GcuSubFrame]["target_longitude_raw"]
    sub = GcuSubFrame(target_distance_raw=10, target_longitude_raw=field.raw_high + 1)
    flagged = GcuPacket(GcuMainFrame(), sub, version=3).anomalies
    assert [a.field for a in flagged] == ["version", "target_longitude_raw"]
    assert flagged[1].value == field.raw_high + 1 and flagged[1].high == field.raw_high
    with pytest.raises(FieldRangeError, match="target_longitude_raw"):
        GcuPacket(GcuMainFrame(), sub).encode()
    assert GcuPacket(GcuMainFrame(), None).anomalies == ()


def test_the_simulator_gives_every_sub_frame_field_a_value() -> None:
    """The simulator builds its GCU sub frame positionally: a field added to the schema (and
    so to GcuSubFrame, with default 0) must get a value there too, not 0 by omission."""
    from gcu_async.sim import report

    tree = ast.parse(inspect.getsource(report.sub_frame))
    calls = [n for n in ast.walk(tree) if isinstance(n, ast.Call)
             and isinstance(n.func, ast.Name) and n.func.id == "GcuSubFrame"]  # fmt: skip
    assert len(calls) == 1
    given_fields = len(calls[0].args) + len(calls[0].keywords)
    assert given_fields == len(FRAME_SCHEMAS[GcuSubFrame].fields)
