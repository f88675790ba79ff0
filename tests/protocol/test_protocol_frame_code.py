"""The frame classes are the code their tables give, and ``as_dict`` has its TypedDict's shape.

The frame classes (``GcuMainFrame`` … ``HostSubFrame``) are generated from the frame tables
(``gcu_frame_tables``, ``host_frame_tables``) by ``tools/gen_frames.py`` into the frame
modules (``gcu_frames``, ``host_frames``), between two marker lines; the committed code must
be what the tables give now (edit a table, run the tool). Each frame's ``as_dict``
returns its ``TypedDict``: the dictionary has exactly the keys the TypedDict declares, so a
type checker's view of it is the run-time one.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest
from hypothesis import given

from gcu_async.protocol import gcu_frame_tables, gcu_frames, host_frames, packets
from gcu_async.protocol.enums import Mode
from gcu_async.protocol.fields import WireField
from gcu_async.protocol.frame_schema import Code, FrameSchema, Value
from helpers.protocol.strategies import gcu_packets, host_packets

TOOL = Path(__file__).resolve().parents[2] / "tools" / "gen_frames.py"


def _tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("gen_frames", TOOL)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("gen_frames", module)
    spec.loader.exec_module(module)
    return module


GEN = _tool()


@pytest.mark.parametrize("module", GEN.MODULES, ids=lambda m: m.__name__)
def test_the_generated_frames_are_what_the_tables_give(module: ModuleType) -> None:
    assert GEN.current(module) == GEN.render(module), (
        f"{GEN.source_path(module).name}: the generated frame classes are not what the tables "
        f"of {module.__name__} give: run tools/gen_frames.py")


def test_a_table_change_changes_the_code(monkeypatch: pytest.MonkeyPatch) -> None:
    """The comparison above is not vacuous: a field added to a table (the worked example of
    docs/architecture.md, "Adding a frame field") changes the generated class, its
    ``build`` keyword, ``as_dict`` and TypedDict."""
    schema = gcu_frame_tables.GCU_SUB_SCHEMA
    fields = (*schema.fields, WireField("humidity_raw", "B", "pod humidity", 0, 100, unit="%",
                                        raw_unit="%"))  # fmt: skip
    views = (*schema.views, Value(name="humidity_raw", fields=("humidity_raw",)))
    bigger = FrameSchema(schema.cls_name, schema.title, schema.start, schema.size, fields,
                         views, header=schema.header)  # fmt: skip
    monkeypatch.setattr(gcu_frame_tables, "GCU_SUB_SCHEMA", bigger)
    code = GEN.render(gcu_frame_tables)
    assert code != GEN.current(gcu_frame_tables)
    assert '    humidity_raw: int = 0\n    """Byte 67, U8, [0, 100]: pod humidity."""' in code
    assert "        humidity_raw: int = 0,\n" in code  # the build keyword
    assert '"humidity_raw": self.humidity_raw,' in code and "    humidity_raw: int\n" in code


def test_a_field_no_view_writes_is_refused() -> None:
    schema = FrameSchema("T", "test frame", 5, 4, (WireField("a", "h"), WireField("b", "h")),
                         (Value(name="a", fields=("a",)),))  # fmt: skip
    module = ModuleType("frames")
    module.T_SCHEMA = schema  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match=r"no view writes \['b'\]"):
        GEN.render(module)


def test_a_name_the_frame_module_does_not_import_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The generated code names what the frame module imports above its marker line: an enum
    (or read function, class) a table uses and the frame module does not import is an error
    naming it, not code that fails later."""
    tables = ModuleType("t_tables")
    tables.__file__ = str(tmp_path / "t_tables.py")
    tables.T_SCHEMA = FrameSchema(  # type: ignore[attr-defined]
        "T", "test frame", 5, 2, (WireField("mode_raw", "B"), WireField("b", "B")),
        (Code(name="mode", fields=("mode_raw",), enum=Mode, doc="Mode."),
         Value(name="b", fields=("b",))))  # fmt: skip
    monkeypatch.setitem(GEN.TARGETS, tables, "t.py")
    frames = tmp_path / "t.py"
    frames.write_text("from gcu_async.protocol.enums import PodModel\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"t\.py does not import Mode from gcu_async\."):
        GEN.render(tables)
    frames.write_text("from gcu_async.protocol.enums import Mode\n", encoding="utf-8")
    assert "        return Mode(self.mode_raw)\n" in GEN.render(tables)


def _keys(typed: Any) -> tuple[set[str], set[str]]:
    return set(typed.__required_keys__), set(typed.__optional_keys__)


TYPED = {gcu_frames.GcuMainFrame: gcu_frames.GcuMainFrameDict,
         gcu_frames.GcuSubFrame: gcu_frames.GcuSubFrameDict,
         host_frames.HostMainFrame: host_frames.HostMainFrameDict,
         host_frames.HostSubFrame: host_frames.HostSubFrameDict,
         gcu_frames.UnknownSubFrame: gcu_frames.UnknownSubFrameDict}  # fmt: skip


def _check_shape(value: dict[str, Any], typed: Any) -> None:
    """``value`` has exactly ``typed``'s required keys and none but its optional ones."""
    required, optional = _keys(typed)
    assert required <= set(value) <= required | optional, (typed.__name__, set(value))


def _check_packet(packet: Any, typed: Any) -> None:
    shown = packet.as_dict()
    _check_shape(shown, typed)
    assert ("anomalies" in shown) == bool(packet.anomalies)
    _check_shape(shown["main"], TYPED[type(packet.main)])
    if packet.sub is None:
        assert shown["sub"] is None
    else:
        _check_shape(shown["sub"], TYPED[type(packet.sub)])
    json.dumps(shown)  # JSON-ready


@given(packet=host_packets)
def test_a_host_packet_dict_has_its_typed_dict_keys(packet: packets.HostPacket) -> None:
    _check_packet(packet, packets.HostPacketDict)


@given(packet=gcu_packets)
def test_a_gcu_packet_dict_has_its_typed_dict_keys(packet: packets.GcuPacket) -> None:
    _check_packet(packet, packets.GcuPacketDict)


@pytest.mark.parametrize(("frame", "typed"), [
    (gcu_frames.GcuMainFrame(), gcu_frames.GcuMainFrameDict),
    (gcu_frames.GcuSubFrame(target_distance_raw=5), gcu_frames.GcuSubFrameDict),
    (host_frames.HostMainFrame(), host_frames.HostMainFrameDict),
    (host_frames.HostSubFrame(), host_frames.HostSubFrameDict),
    (gcu_frames.UnknownSubFrame(7, bytes(31)), gcu_frames.UnknownSubFrameDict),
], ids=lambda x: type(x).__name__)  # fmt: skip
def test_each_frame_dict_has_exactly_its_typed_dict_keys(frame: Any, typed: Any) -> None:
    shown = frame.as_dict()
    assert set(shown) == _keys(typed)[0] and not _keys(typed)[1]
