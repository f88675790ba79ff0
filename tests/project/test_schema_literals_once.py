"""Every numeric range of the protocol schema is written once in ``src/``, and so is every
opcode and frame byte offset (the second half of this file).

The schema (:mod:`gcu_async.protocol.fields`'s ``WireField``\\ s, gathered from every frame
schema and every command's parameters) is where a field's raw range lives; everything else
derives from it. This test reads every ``src/`` module with :mod:`tokenize` and fails on a
copy of a range: in code outside the schema modules, both ends of one field's range, as raw
integers or in engineering units, written on one logical line (``-18000, 17999``,
``(-90.0, 90.0)``), or a distinctive bound on its own (one no wire type, clock or unit
conversion explains, such as ``36000``); inside the schema modules, one range written on two
lines; in any string or docstring, a range in range notation (``[0, 360)``, ``±180°``,
``-90 … 90``), a distinctive bound or an opcode. A few numbers that equal a field's range
are facts of geometry or of MAVLink instead (``ALLOWED``, ``STRING_ALLOWED``, each with its
reason and a test that it still hides something). The frame classes generated from the frame
tables (between the marker lines of the frame modules) are derived and skipped:
tests/protocol/test_protocol_frame_code.py holds them to the tables.
"""

from __future__ import annotations

import importlib
import io
import pkgutil
import re
import tokenize
from collections.abc import Iterator
from pathlib import Path

import gcu_async.protocol
from gcu_async.protocol.fields import WIRE_RANGES, WireField

SRC = Path(gcu_async.protocol.__file__).resolve().parents[1]

SCHEMA_MODULES = {
    "protocol/fields.py",
    "protocol/frame_schema.py",
    "protocol/command_fields.py",
    "protocol/commands.py",
    "protocol/opcodes.py",
    "protocol/gcu_frame_tables.py",
    "protocol/headings.py",
    "protocol/host_frame_tables.py",
    "protocol/layout.py",
}
"""Where the schema is written: its tables, and the field kinds that read them."""

COMMON = {0, 1, 2, 10, 60, 100, 1000, 3600, 10000, 86400}
"""Numbers too common to mean one range on their own (they count only in pairs): small
integers, percent, the time and unit conversions (ms per s, s per hour, s per day), and
round counts (10,000 datagrams, 10 km, 10 ms in µs)."""


COMMON_PAIRS = {(0.0, 100.0)}
"""Pairs too common to mean one field: 0–100 is every percentage (a zoom's share of its
range, a count of examples), whichever field also has it."""

SMALL = 10
"""A range within ±10 (a switch's 0–1, a choice of a few, a palette) is too common to count as
a copy: small integers are everywhere."""

ALLOWED = {
    ("protocol/units.py", "max(-90.0, min(90.0, lat))"):
        "offset_position keeps a latitude on the sphere: geometry, not a field's range",
    ("protocol/units.py", "return 0.0 if wrapped >= 360.0 else wrapped"):
        "wrap_degrees_360 is the circle's arithmetic",
    ("bridge/bridge.py", "if not 1 <= system_id <= 255:"):
        "MAVLink's system id range, not the camera mask's",
    ("sim/motion.py", "ABSOLUTE_PITCH_LIMITS = (-90.0, 90.0)"):
        "the simulated pod's mechanical pitch stops, a model choice (docs/simulator.md)",
}
"""(file, text of the line) → why these numbers there are not a copy of a schema range."""


def _fields(obj: object, seen: set[int], depth: int = 0) -> Iterator[WireField]:
    if depth > 6 or id(obj) in seen:
        return
    seen.add(id(obj))
    if isinstance(obj, WireField):
        yield obj
    elif isinstance(obj, (tuple, list, frozenset, set)):
        for item in obj:
            yield from _fields(item, seen, depth + 1)
    elif isinstance(obj, dict):
        for item in obj.values():
            yield from _fields(item, seen, depth + 1)
    else:
        for attr in ("fields", "wire", "params", "SCHEMA"):
            part = getattr(obj, attr, None)
            if part is not None and not callable(part):
                yield from _fields(part, seen, depth + 1)


def schema_fields() -> list[WireField]:
    """Every WireField reachable from the globals of the ``gcu_async.protocol`` modules."""
    seen: set[int] = set()
    found: dict[int, WireField] = {}
    for info in pkgutil.iter_modules(gcu_async.protocol.__path__, "gcu_async.protocol."):
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            for f in _fields(value, seen):
                found[id(f)] = f
    return list(found.values())


def _ranges() -> set[tuple[float, float]]:
    """Each narrowed range, raw and in engineering units (wire-type ranges are no fact)."""
    ranges: set[tuple[float, float]] = set()
    for f in schema_fields():
        if f.low is None and f.high is None:
            continue
        high = WIRE_RANGES[f.fmt][1] if f.high is None else f.high
        raw = (f.raw_low, high)
        if raw == WIRE_RANGES[f.fmt]:
            continue
        ranges.add(raw)
        if f.high_open:
            ranges.add((f.raw_low, f.raw_high))
        if f.scale != 1:
            ranges.add((round(f.raw_low / f.scale, 10), round(high / f.scale, 10)))
    return ranges


_KEYWORDS = {"return", "in", "else", "and", "or", "not", "if", "lambda", "yield", "assert"}
_BEFORE_UNARY = {"(", "[", "{", ",", "=", ":", "==", "!=", "<", ">", "<=", ">=", "+", "*", "/",
                 "%", "**", "//", "-", *_KEYWORDS}


def _numbers(path: Path) -> Iterator[tuple[int, list[float]]]:
    """Each logical line's numeric literals (a unary minus applied), by first line number."""
    tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
    line: list[float] = []
    start = 0
    minus = False
    previous = "("
    for tok in tokens:
        if tok.type in (tokenize.NEWLINE, tokenize.ENDMARKER):
            if line:
                yield start, line
            line, start = [], 0
            continue
        if tok.type == tokenize.NUMBER and "j" not in tok.string.lower():
            value = float(eval(tok.string))  # a literal: int, float, hex, underscores
            line.append(-value if minus else value)
            start = start or tok.start[0]
        # a unary minus follows an operator, an opening bracket or a keyword, never an operand
        minus = tok.type == tokenize.OP and tok.string == "-" and previous in _BEFORE_UNARY
        if tok.type == tokenize.OP or (tok.type == tokenize.NAME and tok.string in _KEYWORDS):
            previous = tok.string
        elif tok.type not in (tokenize.NL, tokenize.COMMENT):
            previous = "operand"


def _copies(ranges: set[tuple[float, float]], root: Path = SRC) -> list[str]:
    bounds = {v for r in ranges for v in r}
    wire = {v for r in WIRE_RANGES.values() for v in r} | {v + 1 for r in WIRE_RANGES.values()
                                                          for v in r}  # fmt: skip
    distinctive = {v for v in bounds if abs(v) >= 1000 and v not in wire and v not in COMMON}
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel in SCHEMA_MODULES:
            continue
        lines = path.read_text(encoding="utf-8").splitlines()
        skip = _generated_lines(path)
        for lineno, numbers in _numbers(path):
            if lineno in skip or any(rel == f and text in lines[lineno - 1] for f, text in ALLOWED):
                continue
            present = set(numbers)
            pairs = [r for r in ranges if r[0] in present and r[1] in present
                     and max(abs(r[0]), abs(r[1])) > SMALL and r not in COMMON_PAIRS]  # fmt: skip
            loners = sorted(present & distinctive)
            if pairs or loners:
                what = pairs[0] if pairs else loners
                found.append(f"{rel}:{lineno}: {what}")
    return found


def test_every_allowance_is_still_needed() -> None:
    """An allowance whose line is gone or no longer matches is dropped, not kept."""
    ranges = _ranges()
    bounds = {v for r in ranges for v in r}
    for (rel, text), why in ALLOWED.items():
        source = (SRC / rel).read_text(encoding="utf-8")
        assert text in source, f"{rel}: {text!r} is gone ({why}): drop the allowance"
        assert any(v in bounds for _, ns in _numbers(SRC / rel) for v in ns), rel


def test_the_schema_is_found() -> None:
    names = {f.name for f in schema_fields()}
    assert {"yaw_raw", "pitch_raw", "gnss_week"} <= names, sorted(names)
    assert len(_ranges()) >= 10


def test_no_range_of_the_schema_is_written_outside_it() -> None:
    copies = _copies(_ranges())
    assert not copies, "range literals of the schema written again outside it:\n" + "\n".join(
        copies)


def test_a_copy_is_caught(tmp_path: Path) -> None:
    """The scan finds a pair, raw or in units, and a lone distinctive bound (it is not
    vacuous), and skips the schema modules."""
    ranges = _ranges()
    raw = next(r for r in sorted(ranges) if r[0] < 0 < r[1])
    lone = next(v for r in sorted(ranges) for v in r if abs(v) >= 1000 and v not in COMMON
                and v not in {w for wr in WIRE_RANGES.values() for w in wr})  # fmt: skip
    (tmp_path / "pair.py").write_text(f"LIMITS = ({raw[0]!r}, {raw[1]!r})\n", encoding="utf-8")
    (tmp_path / "lone.py").write_text(f"def f(x):\n    return x > {lone!r}\n", encoding="utf-8")
    (tmp_path / "protocol").mkdir()
    (tmp_path / "protocol" / "fields.py").write_text(f"R = {raw!r}\n", encoding="utf-8")
    found = _copies(ranges, tmp_path)
    assert [f.split(":")[0] for f in found] == ["lone.py", "pair.py"], found


# -- opcodes and byte offsets ---------------------------------------------------------------
# An opcode is written once, as its ``Opcode`` member (commands.py); a byte offset once, in
# layout.py and the frame schemas (each field's offset derives from the table's order).
# Outside them, three kinds of literal are copies: a hex literal that is an opcode (from 0x10:
# 0x00-0x08 are everyday bit values), a frame boundary (bytes 36-38, 68-70) anywhere, and a
# field's byte offset as a subscript or slice bound (``raw[69]``, ``raw[5:37]``).

OPCODE_ALLOWED = {
    ("protocol/enums.py", "ANGLE_CONTROL = 0x10"): "Mode bytes: the GCU's reported mode, "
    "a fact of its own whose values V2.0.6 took from the opcodes entering each mode",
    ("protocol/enums.py", "POINTING_LOCK = 0x11"): "Mode byte",
    ("protocol/enums.py", "POINTING_FOLLOW = 0x12"): "Mode byte",
    ("protocol/enums.py", "TOP_DOWN = 0x13"): "Mode byte",
    ("protocol/enums.py", "EULER_CONTROL = 0x14"): "Mode byte",
    ("protocol/enums.py", "GAZE = 0x16"): "Mode byte",
    ("protocol/enums.py", "TRACK = 0x17"): "Mode byte",
    ("protocol/enums.py", "FPV = 0x1C"): "Mode byte",
    ("capture/synth.py", "SYN, FIN, RST, PSH, ACK = 0x02, 0x01, 0x04, 0x08, 0x10"):
        "TCP header flags",
    ("capture/blocks.py", "2.0 ** -(value & 0x7F) if value & 0x80"):
        "pcapng if_tsresol: bit 7 chooses a power of two",
}
"""(file, text of the line) → why a hex literal there that equals an opcode is no copy."""

FOREIGN_LAYOUTS = {
    "capture/blocks.py": "pcapng block layouts",
    "sim/udp.py": "the kernel's struct ifreq",
    "transport/_datagram.py": "socket addresses (sockaddr_in, sockaddr_in6)",
    "cli/decode.py": "the width of a token shown in an error message",
    "wireshark/__init__.py": "a digest's first 16 hex digits",
}
"""Files whose subscripts index other formats than V2.0.6 packets."""


def frame_offsets() -> tuple[set[int], set[int]]:
    """(every field's byte offset in a packet, the frame boundaries around the sub frame)."""
    from gcu_async.protocol import layout
    from gcu_async.protocol.gcu_frame_tables import GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA
    from gcu_async.protocol.host_frame_tables import HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA

    fields = {layout.SUB_HEADER_OFFSET, layout.OPCODE_OFFSET, layout.OPCODE_OFFSET + 1}
    for schema in (GCU_MAIN_SCHEMA, GCU_SUB_SCHEMA, HOST_MAIN_SCHEMA, HOST_SUB_SCHEMA):
        fields |= set(schema.offsets.values())
    main_end = layout.MAIN_START + layout.MAIN_SIZE - 1
    sub_end = layout.SUB_START + layout.SUB_SIZE - 1
    boundaries = {main_end, layout.SUB_HEADER_OFFSET, layout.SUB_START, sub_end,
                  layout.OPCODE_OFFSET, layout.OPCODE_OFFSET + 1}  # fmt: skip
    return fields, boundaries


def _literals(path: Path) -> Iterator[tuple[int, str, int, bool]]:
    """Each integer literal: (line, its text, its value, written as a subscript or slice
    bound)."""
    tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
    previous, depth = "", 0
    for tok in tokens:
        if tok.type == tokenize.NUMBER and not any(ch in tok.string.lower() for ch in ".ej"):
            yield tok.start[0], tok.string, int(tok.string, 0), depth > 0 and previous in "[:"
        if tok.type == tokenize.OP and tok.string in "[]":
            depth = depth + 1 if tok.string == "[" else max(0, depth - 1)
        if tok.type not in (tokenize.NL, tokenize.COMMENT, tokenize.NEWLINE):
            previous = tok.string


def _opcode_offset_copies(root: Path = SRC) -> list[str]:
    from gcu_async.protocol.commands import Opcode

    opcodes = {int(o) for o in Opcode if o >= 0x10}
    fields, boundaries = frame_offsets()
    found = []
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        if rel in SCHEMA_MODULES:
            continue
        lines = path.read_text(encoding="utf-8").splitlines()
        skip = _generated_lines(path)
        for lineno, text, value, subscript in _literals(path):
            if lineno in skip:
                continue
            line = lines[lineno - 1]
            if text.lower().startswith("0x") and value in opcodes:
                if not any(rel == f and t in line for f, t in OPCODE_ALLOWED):
                    found.append(f"{rel}:{lineno}: opcode {text}")
            elif not text.lower().startswith("0x") and value in boundaries:
                found.append(f"{rel}:{lineno}: frame boundary {text}")
            elif subscript and value in fields and rel not in FOREIGN_LAYOUTS:
                found.append(f"{rel}:{lineno}: byte offset {text}")
    return found


def test_no_opcode_or_offset_is_written_outside_the_schema() -> None:
    copies = _opcode_offset_copies()
    assert not copies, "opcodes or byte offsets written again outside the schema:\n" + "\n".join(
        copies)


def test_every_opcode_offset_allowance_is_still_needed() -> None:
    for (rel, text), why in OPCODE_ALLOWED.items():
        assert text in (SRC / rel).read_text(encoding="utf-8"), f"{rel}: {text!r} is gone ({why})"
    for rel in FOREIGN_LAYOUTS:
        fields, _ = frame_offsets()
        assert any(s and v in fields for _, _, v, s in _literals(SRC / rel)), rel


def test_an_opcode_or_offset_copy_is_caught(tmp_path: Path) -> None:
    """The scan finds an opcode in hex, a frame boundary and a field offset in a subscript,
    and skips the schema modules, docstrings, comments and small subscripts."""
    (tmp_path / "opcode.py").write_text("def f(op):\n    return op == 0x25\n", encoding="utf-8")
    (tmp_path / "boundary.py").write_text("END = 69\n", encoding="utf-8")
    (tmp_path / "offset.py").write_text("def f(raw):\n    return raw[41]\n", encoding="utf-8")
    (tmp_path / "fine.py").write_text('"""0x25 in a docstring."""\nX = raw[3]  # 0x81\n',
                                      encoding="utf-8")  # fmt: skip
    (tmp_path / "protocol").mkdir()
    (tmp_path / "protocol" / "layout.py").write_text("OPCODE_OFFSET = 69\n", encoding="utf-8")
    found = _opcode_offset_copies(tmp_path)
    assert [f.split(":")[0] for f in found] == ["boundary.py", "offset.py", "opcode.py"], found


# -- inside the schema modules, and in strings and docstrings -------------------------------
# A range written on two lines of the schema modules is written twice (a shared range is one
# named constant: fields.LONGITUDE_RANGE, headings.heading). In a string or docstring of any
# module, a range in range notation, a distinctive bound or an opcode is a copy: the words say
# "the field's range" and name the field, the constant or the command.

GENERATED = ("# --- generated by tools/gen_frames.py", "# --- end of generated code ---")
"""The marker lines around the frame classes generated from the frame tables."""

PENDING: dict[str, tuple[str, str, int]] = {}
"""file → (its owner in this phase, what the scan finds there, how many findings): copies in
files of others, left for their owners; the integrator removes each entry once it is fixed
(test_every_pending_entry_is_still_needed fails while one finds less than it says). Empty:
every string names the field, the constant or the command instead."""

STRING_ALLOWED = {
    ("protocol/units.py", "Wrap an angle into [0, 360)"):
        "wrap_degrees_360's contract is the circle's arithmetic (as ALLOWED says of its code)",
    ("protocol/units.py", "Wrap an angle into [-180, 180)"):
        "wrap_degrees_180's contract, the circle's arithmetic",
    ("protocol/units.py", "within ±90°, longitude wrapped to [-180, 180)"):
        "offset_position keeps a position on the sphere: geometry (as ALLOWED says of its code)",
    ("bridge/geometry.py", "roll and yaw in [-180, 180), pitch in\n    [-90, 90]"):
        "the ranges of Euler angles from a quaternion (atan2, asin): geometry",
    ("bridge/bridge.py", "is outside the allowed range [1, 255]"):
        "MAVLink's system id range, not the camera mask's (as ALLOWED says of its check)",
}
"""(file, text inside one of its strings) → why the numbers there are not a copy of a schema
range: facts of geometry or of MAVLink that happen to equal a field's range. The text is
blanked before the scan, so the rest of that string is still read."""

_NUMBER = r"[-−]?\d[\d_]*(?:\.\d+)?"
_RANGE_NOTATION = re.compile(
    rf"[\[(]\s*(?P<a>{_NUMBER})\s*°?\s*,\s*(?P<b>{_NUMBER})\s*°?\s*[\])]"
    rf"|(?<![\w.])(?P<c>{_NUMBER})\s*(?:°|deg)?\s*(?:…|\.\.\.?|–|—| to )\s*(?P<d>{_NUMBER})"
    rf"|±\s*(?P<e>\d[\d_]*(?:\.\d+)?)")
_LONE = re.compile(rf"(?<![\w.]){_NUMBER}(?![\w.])")
_HEX = re.compile(r"(?<![\w])0[xX][0-9A-Fa-f]+(?![\w])")


def _value(text: str) -> float:
    return float(text.replace("−", "-").replace("_", ""))


def _generated_lines(path: Path) -> set[int]:
    """The line numbers of ``path``'s generated code (none outside the frame modules)."""
    lines = path.read_text(encoding="utf-8").splitlines()
    starts = [i for i, line in enumerate(lines, 1) if line.startswith(GENERATED[0])]
    ends = [i for i, line in enumerate(lines, 1) if line.startswith(GENERATED[1])]
    return {n for a, b in zip(starts, ends, strict=True) for n in range(a, b + 1)}


def _strings(path: Path) -> Iterator[tuple[int, str]]:
    """Each string literal and docstring outside generated code: (first line, its text)."""
    skip = _generated_lines(path)
    tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
    # Python 3.12 tokenizes an f-string in parts (PEP 701): its literal parts, joined with
    # the source of each replacement field, are the string (as one STRING token before).
    fstring = getattr(tokenize, "FSTRING_START", None)
    parts: list[tuple[int, str]] = []  # (line, text) of the open f-strings' pieces, nested
    depth = 0
    for tok in tokens:
        if fstring is not None and tok.type == fstring:
            depth += 1
            parts.append((tok.start[0], tok.string))
        elif depth and tok.type == tokenize.FSTRING_END:  # type: ignore[attr-defined]
            depth -= 1
            if depth == 0:
                first = parts[0][0]
                if first not in skip:
                    yield first, "".join(t for _, t in parts) + tok.string
                parts = []
            else:
                parts.append((tok.start[0], tok.string))
        elif depth:
            parts.append((tok.start[0], tok.string))
        elif tok.type == tokenize.STRING and tok.start[0] not in skip:
            yield tok.start[0], tok.string


def _string_findings(text: str, ranges: set[tuple[float, float]], distinctive: set[float],
                     opcodes: set[int]) -> list[str]:  # fmt: skip
    found = []
    for m in _RANGE_NOTATION.finditer(text):
        if m["e"] is not None:
            pair = (-_value(m["e"]), _value(m["e"]))
        else:
            pair = (_value(m["a"] or m["c"]), _value(m["b"] or m["d"]))
        if pair in ranges and max(map(abs, pair)) > SMALL and pair not in COMMON_PAIRS:
            found.append(f"range {m[0]!r}")
    found += [f"bound {n!r}" for n in _LONE.findall(text) if _value(n) in distinctive]
    found += [f"opcode {h}" for h in _HEX.findall(text) if int(h, 16) in opcodes]
    return found


def _distinctive(ranges: set[tuple[float, float]]) -> set[float]:
    bounds = {v for r in ranges for v in r}
    wire = {v for r in WIRE_RANGES.values() for v in r} | {v + 1 for r in WIRE_RANGES.values()
                                                          for v in r}  # fmt: skip
    return {v for v in bounds if abs(v) >= 1000 and v not in wire and v not in COMMON}


def string_copies(root: Path = SRC) -> dict[str, list[str]]:
    """file → each range, distinctive bound or opcode written in its strings."""
    from gcu_async.protocol.commands import Opcode

    ranges = _ranges()
    distinctive = _distinctive(ranges)
    opcodes = {int(o) for o in Opcode if o >= 0x10}
    found: dict[str, list[str]] = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).as_posix()
        allowed = [t for f, t in STRING_ALLOWED if f == rel]
        for line, text in _strings(path):
            for t in allowed:
                text = text.replace(t, " " * len(t))
            for what in _string_findings(text, ranges, distinctive, opcodes):
                found.setdefault(rel, []).append(f"{rel}:{line}: {what}")
    return found


def schema_twice(root: Path = SRC) -> list[str]:
    """A range of the schema written on two lines of the schema modules (code only)."""
    ranges = _ranges()
    seen: dict[tuple[float, float], list[str]] = {}
    for rel in sorted(SCHEMA_MODULES):
        path = root / rel
        if not path.exists():
            continue
        skip = _generated_lines(path)
        tokens = tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline)
        by_line: dict[int, set[float]] = {}
        minus, previous = False, "("
        for tok in tokens:
            if tok.type == tokenize.NUMBER and tok.start[0] not in skip and "j" not in tok.string:
                value = float(eval(tok.string))  # a literal: int, float, hex, underscores
                by_line.setdefault(tok.start[0], set()).add(-value if minus else value)
            minus = tok.type == tokenize.OP and tok.string == "-" and previous in _BEFORE_UNARY
            if tok.type == tokenize.OP or (tok.type == tokenize.NAME and tok.string in _KEYWORDS):
                previous = tok.string
            elif tok.type not in (tokenize.NL, tokenize.COMMENT, tokenize.NEWLINE):
                previous = "operand"
        for line, present in by_line.items():
            for r in ranges:
                if (r[0] in present and r[1] in present and max(map(abs, r)) > SMALL
                        and r not in COMMON_PAIRS):  # fmt: skip
                    seen.setdefault(r, []).append(f"{rel}:{line}")
    return [f"{r}: {', '.join(where)}" for r, where in sorted(seen.items()) if len(where) > 1]


PENDING_TWICE: dict[str, tuple[str, str, int]] = {}
"""Schema module → (owner, what, how many ranges it writes again): left for their owners.
Empty: a shared range is one named constant."""


def test_no_range_is_written_twice_in_the_schema_modules() -> None:
    twice = schema_twice()
    fresh = [t for t in twice if not any(rel in t for rel in PENDING_TWICE)]
    assert not fresh, "ranges written on two lines of the schema modules:\n" + "\n".join(fresh)
    for rel, (_, _, n) in PENDING_TWICE.items():
        assert sum(rel in t for t in twice) == n, (rel, twice)


def test_no_range_or_opcode_is_written_in_a_string() -> None:
    found = string_copies()
    fresh = {rel: items for rel, items in found.items() if rel not in PENDING}
    assert not fresh, "ranges, bounds or opcodes written in strings:\n" + "\n".join(
        i for items in fresh.values() for i in items)
    grown = {rel: len(found[rel]) for rel, (_, _, n) in PENDING.items()
             if len(found.get(rel, ())) > n}  # fmt: skip
    assert not grown, f"more copies than PENDING allows: {grown}"


def test_every_pending_entry_is_still_needed() -> None:
    """A pending entry whose file holds fewer copies than it says is lowered or dropped."""
    found = string_copies()
    stale = {rel: (n, len(found.get(rel, ()))) for rel, (_, _, n) in PENDING.items()
             if len(found.get(rel, ())) < n}  # fmt: skip
    assert not stale, f"pending entries to lower or drop (said, found): {stale}"


def test_every_string_allowance_is_still_needed() -> None:
    """An allowed text is still in its file's strings and still holds a finding of its own
    (an allowance that hides nothing is dropped, not kept)."""
    from gcu_async.protocol.commands import Opcode

    ranges = _ranges()
    distinctive = _distinctive(ranges)
    opcodes = {int(o) for o in Opcode if o >= 0x10}
    for (rel, text), why in STRING_ALLOWED.items():
        strings = [s for _, s in _strings(SRC / rel)]
        assert any(text in s for s in strings), f"{rel}: {text!r} is gone ({why})"
        assert _string_findings(text, ranges, distinctive, opcodes), (rel, text)


def test_a_string_copy_is_caught(tmp_path: Path) -> None:
    """Range notation, a distinctive bound and an opcode in a docstring are found, in any
    module (the schema modules too), and generated code is skipped."""
    lone = int(next(v for v in sorted(_distinctive(_ranges()))))
    (tmp_path / "protocol").mkdir()
    (tmp_path / "protocol" / "fields.py").write_text(
        '"""Pitch within ±90 deg."""\n', encoding="utf-8")
    (tmp_path / "docs.py").write_text(
        f'"""Yaw in [0, 360) deg, up to {lone}; sends 0x25."""\n', encoding="utf-8")
    (tmp_path / "generated.py").write_text(
        f'{GENERATED[0]}\n"""[0, 360)"""\n{GENERATED[1]}\n"""[0, 10)"""\n', encoding="utf-8")
    found = string_copies(tmp_path)
    assert sorted(found) == ["docs.py", "protocol/fields.py"], found
    assert len(found["docs.py"]) == 3 and "range '±90'" in found["protocol/fields.py"][0]


def test_a_range_twice_in_the_schema_modules_is_caught(tmp_path: Path) -> None:
    (tmp_path / "protocol").mkdir()
    (tmp_path / "protocol" / "fields.py").write_text(
        "A = (-1800000000, 1800000000)\nB = (-1800000000, 1800000000)\n", encoding="utf-8")
    assert schema_twice(tmp_path) == [
        "(-1800000000, 1800000000): protocol/fields.py:1, protocol/fields.py:2"]
