"""The dissector's tables, generated from :mod:`gcu_async.protocol` when the dissector is built.

``xfgcu.lua`` decodes frames by hand (an independent second decoder of the library's) and
commands with one generic decoder driven by :func:`render`'s tables:

* the names: opcodes (from the command rows), modes, pod models and their vendor spellings,
  every flag bit, the enums of choice parameters;
* ``COMMAND_ROWS``: per opcode, its parameters in wire order (name, struct code, scale, unit,
  raw range, enum: the command table as plain rows, :func:`wire_rows`);
* what the rows do not say, learnt by asking the library's own receive path
  (:func:`gcu_async.protocol.decode_command`) about raw values, so that the two decoders word
  every value and anomaly alike: how a one-byte field reads (a switch's ``True``/``False``
  and which byte means "on"), which field a value that carries one of several meanings fills
  (``zoom_to``'s ratio or fraction, over the whole wire range), the unit and detail of each
  parameter's range anomaly, and the order rules between two parameters (``box.right`` not
  left of ``box.left``). A row decode does not know yet is decoded from the row alone.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Iterator, Sequence
from enum import IntEnum, IntFlag
from functools import lru_cache
from typing import Any, Literal, NamedTuple

import gcu_async.protocol as protocol
from gcu_async.protocol import AnomalousCommand, decode_command
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.catalogue import CATALOGUE
from gcu_async.protocol.enums import (
    PIP_MODE_MASK,
    CameraFlags,
    FaultFlags,
    HostFlags,
    Mode,
    PodModel,
    PodStatus,
    SubFrameRequest,
    ThermalFlags,
)
from gcu_async.protocol.feedback import CALIBRATION_IN_PROGRESS, THERMAL_OPCODES, ZOOM_OPCODES
from gcu_async.protocol.fields import WIRE_RANGES
from gcu_async.protocol.headings import PAST_TURN_DETAIL, SIGNED_DETAIL, TURN
from gcu_async.protocol.opcodes import Opcode
from gcu_async.protocol.pods import POD_NAMES

FULL_PROBE_BYTES = 2
"""A parameter this wide or narrower may be probed at every raw value its wire type has."""

_MISSING = object()


# -- the command table as plain rows: every command's parameter bytes, field by field ------
class WireParam(NamedTuple):
    """One parameter field on the wire, for table-driven decoders (the Lua dissector)."""

    name: str
    """``"cameras"``, ``"box.left"``, ``"point.x"``."""
    fmt: str
    """One struct code: B b H h I i (little-endian)."""
    scale: float
    """Engineering value = raw / scale (1 for plain integers)."""
    unit: str
    """Engineering unit, ``""`` if none."""
    low: int | None
    """Raw range, inclusive; ``None`` = the wire type's own range."""
    high: int | None
    enum: str | None
    """Name of the IntEnum of a choice field, or of the IntFlag whose bits a mask field names
    (in :mod:`gcu_async.protocol`), else ``None``."""


class WireRow(NamedTuple):
    """One command's parameter bytes, field by field in wire order (a fixed length: the sum
    of its fields' sizes)."""

    opcode: int
    command: str
    """The :class:`~gcu_async.protocol.Opcode` member name, e.g. ``"ZOOM_TO"``."""
    params: tuple[WireParam, ...]


def wire_rows() -> tuple[WireRow, ...]:
    """Every opcode (the null command included), ascending, with its parameter fields (made
    from the command table, :data:`~gcu_async.protocol.COMMAND_TYPES`)."""
    found = []
    for opcode in sorted(protocol.COMMAND_TYPES):
        params = []
        for kind in protocol.COMMAND_TYPES[opcode].SCHEMA.params:
            enum_name = getattr(getattr(kind, "enum", None), "__name__", None)
            for w in kind.wire:
                own = WIRE_RANGES[w.fmt]
                low = None if w.raw_low == own[0] else w.raw_low
                high = None if w.raw_high == own[1] else w.raw_high
                params.append(WireParam(w.name, w.fmt, float(w.scale), w.unit, low, high,
                                        enum_name))  # fmt: skip
        found.append(WireRow(opcode, Opcode(opcode).name, tuple(params)))
    return tuple(found)


def rows() -> tuple[WireRow, ...]:
    """The command rows the tables are generated from (the one place they are read)."""
    return wire_rows()


def _lua_str(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _lua(value: Any) -> str:
    """A Lua literal of ``value`` (None, bool, int, float, str, list/tuple, dict)."""
    if value is None:
        return "nil"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value) if math.isfinite(value) else "0/0"
    if isinstance(value, str):
        return _lua_str(value)
    if isinstance(value, dict):
        items = []
        for k, v in value.items():
            key = k if isinstance(k, str) and k.isidentifier() else f"[{_lua(k)}]"
            items.append(f"{key} = {_lua(v)}")
        return "{" + ", ".join(items) + "}"
    if isinstance(value, (list, tuple)):
        return "{" + ", ".join(_lua(v) for v in value) + "}"
    raise TypeError(f"no Lua literal for {value!r}")


def _names(var: str, enum: type[IntEnum], doc: str) -> list[str]:
    lines = [f"-- {doc}", f"local {var} = {{"]
    for member in enum:
        if int(member) >= 0:  # UNKNOWN = -1 is the library's catch-all, not a wire value
            lines.append(f"  [0x{int(member):02X}] = {_lua_str(member.name or '')},")
    return [*lines, "}"]


def _bits(var: str, flag: type[IntFlag], doc: str) -> list[str]:
    lines = [f"-- {doc}: {{mask, name}} in definition order", f"local {var} = {{"]
    for member in flag:
        lines.append(f"  {{0x{int(member):04X}, {_lua_str(member.name or '')}}},")
    return [*lines, "}"]


def _set(var: str, codes: frozenset[int], doc: str) -> list[str]:
    items = ", ".join(f"[0x{int(c):02X}] = true" for c in sorted(codes))
    return [f"-- {doc}", f"local {var} = {{{items}}}"]


# -- what the receive path says about raw values ---------------------------------------------
def _range(p: WireParam) -> tuple[int, int]:
    wire_low, wire_high = WIRE_RANGES[p.fmt]
    return (wire_low if p.low is None else p.low, wire_high if p.high is None else p.high)


def _enum(p: WireParam) -> type[IntEnum] | type[IntFlag] | None:
    if p.enum is None:
        return None
    found = getattr(protocol, p.enum, None)
    if not (isinstance(found, type) and issubclass(found, (IntEnum, IntFlag))):
        raise LookupError(f"{p.name}: enum {p.enum!r} is not an IntEnum of gcu_async.protocol")
    return found


def _at(params: dict[str, Any], path: str) -> Any:
    value: Any = params
    for key in path.split("."):
        if not isinstance(value, dict) or key not in value:
            return _MISSING
        value = value[key]
    return value


class _Probe:
    """Decodes one row's parameters with chosen raw values."""

    def __init__(self, row: WireRow) -> None:
        self.row = row
        self.layout = struct.Struct("<" + "".join(p.fmt for p in row.params))
        self.base: list[int] | None = None
        for pick in (0, 1):  # every parameter at the bottom of its range, else at the top
            raws = [_range(p)[pick] for p in row.params]
            if self.decode(raws)[0] is not None:
                self.base = raws
                break

    def decode(self, raws: Sequence[int]) -> tuple[dict[str, Any] | None, tuple[Anomaly, ...]]:
        """(JSON parameters, ()) if decode accepts ``raws``, (None, anomalies) if it flags
        them, (None, ()) if it does not know the opcode."""
        command = decode_command(self.row.opcode, self.layout.pack(*raws))
        if isinstance(command, AnomalousCommand):
            return None, command.anomalies
        shown = command.as_dict()
        return (shown["params"], ()) if "params" in shown else (None, ())

    def with_value(self, index: int, raw: int) -> tuple[dict[str, Any] | None, tuple[Anomaly, ...]]:
        assert self.base is not None
        raws = list(self.base)
        raws[index] = raw
        return self.decode(raws)


def _template(found: Anomaly) -> dict[str, Any]:
    return {"field": found.field, "low": found.low, "high": found.high, "unit": found.unit,
            "detail": found.detail}  # fmt: skip


def _number(p: WireParam, raw: int) -> float:
    return raw / p.scale if p.scale != 1 else raw


def _wire_values(p: WireParam) -> range:
    wire_low, wire_high = WIRE_RANGES[p.fmt]
    return range(wire_low, wire_high + 1)


def _learn_param(probe: _Probe, index: int, others: set[str]) -> dict[str, Any]:
    """How decode reads parameter ``index``: extra keys for its Lua row."""
    p = probe.row.params[index]
    low, high = _range(p)
    learnt: dict[str, Any] = {}
    params, _ = probe.with_value(index, low)
    assert params is not None
    if _at(params, p.name) in (_MISSING, None):  # its value fills one of several fields
        if struct.calcsize(p.fmt) > FULL_PROBE_BYTES:
            raise ValueError(f"{probe.row.command}.{p.name}: not in decode's parameters")
        learnt["segments"] = _segments(probe, index, others)
        return learnt
    probes = _wire_values(p) if struct.calcsize(p.fmt) == 1 else (low - 1, low, high, high + 1)
    values: dict[int, Any] = {}
    for raw in probes:
        if raw not in _wire_values(p):
            continue
        params, anomalies = probe.with_value(index, raw)
        if params is not None:
            values[raw] = _at(params, p.name)
        own = [a for a in anomalies if a.field == p.name and a.value == raw]
        outside = struct.calcsize(p.fmt) == 1 or not low <= raw <= high  # not an order rule
        if own and outside and "anomaly" not in learnt:
            learnt["anomaly"] = _template(own[0])
    plain = all(not isinstance(v, bool) and v == _number(p, raw) for raw, v in values.items())
    if isinstance(_enum(p), type) and issubclass(_enum(p), IntEnum):  # type: ignore[arg-type]
        plain = all(isinstance(v, str) for v in values.values())
    if not plain:
        if not all(isinstance(v, bool) for v in values.values()):
            raise ValueError(f"{probe.row.command}.{p.name}: decode shows {values!r}")
        learnt["switch"] = {raw: v for raw, v in sorted(values.items())}
    elif struct.calcsize(p.fmt) == 1 and set(values) != set(range(low, high + 1)):
        raise ValueError(f"{probe.row.command}.{p.name}: decode accepts {sorted(values)}, "
                         f"the row {low}..{high}")  # fmt: skip
    return learnt


def _segments(probe: _Probe, index: int, others: set[str]) -> list[dict[str, Any]]:
    """Runs of raw values that fill the same field with the same scale, or are flagged."""
    p = probe.row.params[index]
    runs: list[dict[str, Any]] = []
    for raw in _wire_values(p):
        params, anomalies = probe.with_value(index, raw)
        key: dict[str, Any]
        if params is None:
            key = {"anomaly": _template(anomalies[0])} if anomalies else {}
        else:
            filled = [(k, v) for k, v in params.items() if k not in others and v is not None]
            if len(filled) != 1 or not isinstance(filled[0][1], float) or filled[0][1] == 0:
                raise ValueError(f"{probe.row.command}.{p.name}={raw}: decode shows {params!r}")
            name, value = filled[0]
            key = {"field": name, "scale": float(f"{raw / value:.12g}")}
        if runs and {k: v for k, v in runs[-1].items() if k not in ("lo", "hi")} == key:
            runs[-1]["hi"] = raw
        else:
            runs.append({"lo": raw, "hi": raw, **key})
    for run in runs:
        if "field" in run:
            run["unit"] = _unit_of(probe.row.opcode, run["field"])
    return runs


def _unit_of(opcode: int, name: str) -> str:
    for entry in CATALOGUE:
        if int(entry.opcode) == opcode:
            for p in entry.parameters:
                if p.name == name:
                    return p.unit
    return ""


def _raise(probe: _Probe, group: Sequence[int], raised: Sequence[int],
           level: int) -> tuple[Anomaly, ...] | None:  # fmt: skip
    """The anomalies of ``group`` at ``level`` with ``raised`` one step above it (``None``:
    accepted)."""
    assert probe.base is not None
    raws = list(probe.base)
    for i in group:
        raws[i] = level + 1 if i in raised else level
    shown, found = probe.decode(raws)
    return None if shown is not None else found


def _reference(one: int, two: int, levels: tuple[int, int], a: str, b: str) -> str | int:
    """What a bound of an order anomaly is, from its values at the two levels: parameter
    ``a`` (raised), ``b`` or a constant."""
    if (one, two) == (levels[0] + 1, levels[1] + 1):
        return a
    if (one, two) == levels:
        return b
    if one == two:
        return one
    raise ValueError(f"order rule of {a} and {b}: a bound reads {one} then {two}")


def _order_rules(probe: _Probe) -> Iterator[dict[str, Any]]:
    """Pairs of parameters decode wants in order (``a`` above ``b`` is flagged), found by
    raising ``a`` one step above the rest of its kind (same struct code and scale), then
    ``b`` with it; each reference of the anomaly (value, low, high) to ``a``, ``b`` or a
    constant, told apart by probing at two levels."""
    params = probe.row.params
    for kind in dict.fromkeys((p.fmt, p.scale) for p in params):
        group = [i for i, p in enumerate(params) if (p.fmt, p.scale) == kind]
        lo = max(_range(params[i])[0] for i in group)
        hi = min(_range(params[i])[1] for i in group)
        if len(group) < 2 or hi - lo < 3:
            continue
        levels = (lo + (hi - lo) // 3, lo + (hi - lo) // 2)
        for a in group:
            flagged = [_raise(probe, group, [a], x) for x in levels]
            if not (flagged[0] and flagged[1]):
                continue
            first, second = flagged[0][0], flagged[1][0]
            for b in group:
                if b == a or any(_raise(probe, group, [a, b], x) is not None for x in levels):
                    continue
                names = (params[a].name, params[b].name)
                yield {"above": names[0], "below": names[1], "field": first.field,
                       "value": _reference(first.value, second.value, levels, *names),
                       "low": _reference(first.low, second.low, levels, *names),
                       "high": _reference(first.high, second.high, levels, *names),
                       "unit": first.unit, "detail": first.detail}  # fmt: skip


def _lua_row(row: WireRow) -> dict[str, Any]:
    probe = _Probe(row) if row.params else None
    known = probe is not None and probe.base is not None
    others = {p.name.split(".")[0] for p in row.params}
    out: list[dict[str, Any]] = []
    for index, p in enumerate(row.params):
        enum = _enum(p)
        kind: Literal["mask", "enum", "number"] = "number"
        if enum is not None:
            kind = "mask" if issubclass(enum, IntFlag) else "enum"
        entry: dict[str, Any] = {"name": p.name, "fmt": p.fmt, "size": struct.calcsize(p.fmt),
                                 "scale": p.scale, "unit": p.unit, "low": _range(p)[0],
                                 "high": _range(p)[1], "kind": kind, "enum": p.enum}  # fmt: skip
        if known:
            assert probe is not None
            entry.update(_learn_param(probe, index, others - {p.name.split(".")[0]}))
        out.append(entry)
    rules = list(_order_rules(probe)) if known and probe is not None else []
    return {"command": row.command, "params": out, "rules": rules}


@lru_cache(maxsize=4)
def _render(command_rows: tuple[WireRow, ...]) -> str:
    vendor = [f"  [0x{int(m):02X}] = {_lua_str(n)}," for m, n in POD_NAMES.items()]
    opcodes = [
        "-- Opcode (byte 69) -> command name (the command rows)",
        "local OPCODE_NAMES = {",
        *(f"  [0x{r.opcode:02X}] = {_lua_str(r.command)}," for r in command_rows),
        "}",
    ]
    enums: dict[str, type[IntEnum]] = {}
    for row in command_rows:
        for p in row.params:
            found = _enum(p)
            if found is not None and not issubclass(found, IntFlag):
                enums[found.__name__] = found
    enum_lines = [
        "-- The enums of choice parameters: name -> {value -> member name}",
        "local PARAM_ENUMS = {",
    ]
    for name, enum in sorted(enums.items()):
        members = ", ".join(f"[{int(m)}] = {_lua_str(m.name or '')}" for m in enum)
        enum_lines.append(f"  {name} = {{{members}}},")
    enum_lines.append("}")
    command_lines = [
        "-- Opcode -> its parameters in wire order (see gcu_async.wireshark.tables)",
        "local COMMAND_ROWS = {",
    ]
    for row in command_rows:
        command_lines.append(f"  [0x{row.opcode:02X}] = {_lua(_lua_row(row))},")
    command_lines.append("}")
    blocks: list[list[str]] = [
        opcodes,
        _names("MODE_NAMES", Mode, "GCU main frame byte 5 -> working mode (Mode)"),
        _names("POD_MODEL_NAMES", PodModel, "Pod code (GCU sub frame byte 40) -> PodModel name"),
        ["-- Pod code -> the vendor's spelling (pods.POD_NAMES)", "local POD_VENDOR_NAMES = {",
         *vendor, "}"],
        _names("SUBFRAME_REQUEST_NAMES", SubFrameRequest, "Host main frame byte 30"),
        _bits("HOST_FLAG_BITS", HostFlags, "Host main frame byte 11 (HostFlags)"),
        _bits("POD_STATUS_BITS", PodStatus, "GCU main frame bytes 6-7 (PodStatus)"),
        _bits("FAULT_BITS", FaultFlags, "GCU sub frame bytes 41-42 (FaultFlags)"),
        _bits("THERMAL_BITS", ThermalFlags, "GCU sub frame byte 63 (ThermalFlags)"),
        _bits("CAMERA_FLAG_BITS", CameraFlags, "GCU sub frame bytes 64-65 (CameraFlags)"),
        _bits("CAMERA_MASK_BITS", protocol.CameraMask, "Camera selection byte (CameraMask)"),
        _set("ZOOM_OPCODES", frozenset(ZOOM_OPCODES),
             "Feedback status of these is a mask of failed cameras"),
        _set("THERMAL_OPCODES", frozenset(THERMAL_OPCODES), "These answer 0x02 on failure"),
        [f"local CALIBRATION_IN_PROGRESS = 0x{CALIBRATION_IN_PROGRESS:02X}",
         f"local PIP_MODE_MASK = 0x{PIP_MODE_MASK:02X}"],
        [f"-- Camera yaw of {TURN} or more: the anomaly's detail by reading (protocol.headings)",
         f"local YAW_SIGNED_DETAIL = {_lua_str(SIGNED_DETAIL)}",
         f"local YAW_PAST_TURN_DETAIL = {_lua_str(PAST_TURN_DETAIL)}"],
        enum_lines,
        command_lines,
    ]  # fmt: skip
    return "\n\n".join("\n".join(block) for block in blocks)


def render() -> str:
    """The generated tables, as Lua (what replaces the marker line of ``xfgcu.lua``)."""
    return _render(tuple(rows()))
