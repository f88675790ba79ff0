"""Every numeric range of the protocol schema is written once in ``src/``.

The schema (:mod:`gcu_async.protocol.fields`'s ``WireField``\\ s, gathered from every frame
schema and every command's parameters) is where a field's raw range lives; everything else
derives from it. This test reads every ``src/`` module outside the schema modules with
:mod:`tokenize` and fails on a copy of a range: both ends of one field's range, as raw
integers or in engineering units, written on one logical line (``-18000, 17999``,
``(-90.0, 90.0)``), or a distinctive bound on its own (one no wire type, clock or unit
conversion explains, such as ``36000``).
"""

from __future__ import annotations

import importlib
import io
import pkgutil
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
    "protocol/gcu_frames.py",
    "protocol/host_frames.py",
    "protocol/layout.py",
}
"""Where the schema is written: its tables, and the field kinds that read them."""

COMMON = {0, 1, 2, 10, 60, 100, 1000, 3600, 10000, 86400}
"""Numbers too common to mean one range on their own (they count only in pairs): small
integers, percent, the time and unit conversions (ms per s, s per hour, s per day), and
round counts (10,000 datagrams, 10 km, 10 ms in µs)."""


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
        for lineno, numbers in _numbers(path):
            if any(rel == f and text in lines[lineno - 1] for f, text in ALLOWED):
                continue
            present = set(numbers)
            pairs = [r for r in ranges if r[0] in present and r[1] in present
                     and max(abs(r[0]), abs(r[1])) > SMALL]  # fmt: skip
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
