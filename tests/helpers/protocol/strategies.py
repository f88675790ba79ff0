"""Hypothesis strategies for every frame, command and packet of the protocol core.

Values are drawn on the wire grid (raw integers in range, or units = raw / scale), so
decode(encode(x)) == x must hold exactly. ``COMMAND_STRATEGIES`` is made from the command
schema: one entry per class in ``COMMAND_TYPES``, with nothing to add for a new command.
"""

from __future__ import annotations

from typing import Any

import crcmod.predefined
from hypothesis import strategies as st

from gcu_async.protocol import (
    COMMAND_TYPES,
    AnomalousCommand,
    CameraMask,
    Command,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    GcuSubFrame,
    HostMainFrame,
    HostPacket,
    HostSubFrame,
    ImageBox,
    ImagePoint,
    UnknownCommand,
    UnknownSubFrame,
    decode_command,
)
from gcu_async.protocol.frame_schema import FrameSchema
from gcu_async.protocol.gcu_frame_tables import GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA
from gcu_async.protocol.host_frame_tables import HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA

S16 = st.integers(-(2**15), 2**15 - 1)
S32 = st.integers(-(2**31), 2**31 - 1)
U8 = st.integers(0, 0xFF)
U16 = st.integers(0, 0xFFFF)
VERSIONS = st.sampled_from([1, 2])

_xmodem = crcmod.predefined.mkCrcFun("xmodem")

# --- frame tables: from the frame schemas ------------------------------------------------
FRAME_SCHEMAS: dict[type[Any], FrameSchema] = {
    HostMainFrame: HOST_MAIN_SCHEMA,
    HostSubFrame: HOST_SUB_SCHEMA,
    GcuMainFrame: GCU_MAIN_SCHEMA,
    GcuSubFrame: GCU_SUB_SCHEMA,
}
"""Each frame class and the schema that describes it."""
FLAGS_INT_RANGE = (0, 0xFFFF)
"""The ``int`` range a flags field is checked in before its reserved bits (``check_flags``)."""


def _frame_ranges(schema: FrameSchema) -> dict[str, tuple[int, int]]:
    return {f.name: FLAGS_INT_RANGE if f.name in schema.flags else (f.raw_low, f.raw_high)
            for f in schema.fields}  # fmt: skip


RAW_RANGES: dict[type[Any], dict[str, tuple[int, int]]] = {
    cls: _frame_ranges(schema) for cls, schema in FRAME_SCHEMAS.items()
}
"""Every raw frame field's allowed range (inclusive): what ``validate()`` / ``encode()``
enforce (``flags_raw`` also has reserved bits)."""


def seal(header: bytes, body: bytes, version: int = 2) -> bytes:
    """A packet assembled by hand (independently of the library's encoder): header, LE
    length, version, ``body`` (bytes 5..S-3), CRC-16/XMODEM high byte first."""
    n = 5 + len(body) + 2
    head = header + n.to_bytes(2, "little") + bytes([version]) + body
    return head + _xmodem(head).to_bytes(2, "big")


# --- frames ---------------------------------------------------------------------------
def frames(cls: type[Any]) -> st.SearchStrategy[Any]:
    """Frames of ``cls`` with every raw field drawn from its schema range (a flags field:
    from the values its defined bits make)."""
    schema = FRAME_SCHEMAS[cls]
    fields: dict[str, st.SearchStrategy[int]] = {}
    for f in schema.fields:
        flags = schema.flags.get(f.name)
        if flags is None:
            fields[f.name] = st.integers(f.raw_low, f.raw_high)
        else:
            bits = [int(m) for m in flags]
            fields[f.name] = st.sets(st.sampled_from(bits)).map(sum)
    return st.builds(cls, **fields)


host_main_frames = frames(HostMainFrame)
host_sub_frames = frames(HostSubFrame)
gcu_main_frames = frames(GcuMainFrame)
gcu_sub_frames = frames(GcuSubFrame)
unknown_sub_frames = st.builds(
    UnknownSubFrame,
    header=U8.filter(lambda h: h != 0x01),
    data=st.binary(min_size=31, max_size=31),
).filter(lambda s: s.header != 0 or any(s.data))
"""Sub frames V2.0.6 does not define: header ≠ 0x01, and not all zero (that is "none")."""

host_subs = st.one_of(st.none(), host_sub_frames, unknown_sub_frames)
gcu_subs = st.one_of(st.none(), gcu_sub_frames, unknown_sub_frames)

# --- commands ---------------------------------------------------------------------------
masks = st.integers(1, 0xFF).map(CameraMask)
fractions = st.integers(0, 10000).map(lambda raw: raw / 10000)
points = st.builds(ImagePoint, fractions, fractions)


@st.composite
def boxes(draw: st.DrawFn) -> ImageBox:
    x0, x1 = sorted((draw(st.integers(0, 10000)), draw(st.integers(0, 10000))))
    y0, y1 = sorted((draw(st.integers(0, 10000)), draw(st.integers(0, 10000))))
    return ImageBox(x0 / 10000, y0 / 10000, x1 / 10000, y1 / 10000)


def _from_schema(cls: type[Command]) -> st.SearchStrategy[Command]:
    """Every command the schema allows: each wire field drawn in its raw range, decoded, kept
    unless a rule across fields (box edges, thresholds, the zoom value's gap, a switch's
    unused byte) rejects it."""
    fields = st.tuples(*(st.integers(w.raw_low, w.raw_high) for w in cls.SCHEMA.wire))
    return (fields.map(lambda raw: decode_command(int(cls.OPCODE), cls.LAYOUT.pack(*raw)))
            .filter(lambda c: not isinstance(c, AnomalousCommand)))  # fmt: skip


COMMAND_STRATEGIES: dict[type[Command], st.SearchStrategy[Command]] = {
    **{cls: _from_schema(cls) for cls in COMMAND_TYPES.values()},
    UnknownCommand: st.builds(
        UnknownCommand,
        code=U8.filter(lambda c: c not in COMMAND_TYPES),
        # up to 184 parameter bytes keeps S within Deframer(header)'s default 256
        params=st.binary(max_size=184),
    ),
}
"""One strategy per command class, made from the command schema."""

commands = st.one_of(*COMMAND_STRATEGIES.values())
feedbacks = st.one_of(
    st.builds(Feedback, opcode=U8, status=st.one_of(st.none(), U8), extra_status=st.just(b"")),
    # more status bytes than V2.0.6 defines (kept, flagged): GCU_MAX_LENGTH allows 15 more
    st.builds(Feedback, opcode=U8, status=U8, extra_status=st.binary(min_size=1, max_size=15)),
)

host_packets = st.builds(
    HostPacket, main=host_main_frames, sub=host_subs, command=commands, version=VERSIONS
)
gcu_packets = st.builds(
    GcuPacket, main=gcu_main_frames, sub=gcu_subs, feedback=feedbacks, version=VERSIONS
)
