"""A command added to the protocol reaches Wireshark with no edit to the dissector.

The dissector's tables are generated from the command rows when it is written; here the rows
gain one the protocol does not have (``EXAMPLE_DEFOG`` at the first free opcode from 0x82, one
U8 parameter 0-2, like the "defog" example of docs/architecture.md's "Changing the
protocol"), and real tshark, with the
dissector written from them, shows the command by name with its parameter, its value, the
range check and the length check, and names the GCU's feedback to it. The packaged
``xfgcu.lua`` is the same file before and after. A second row (a camera mask, a scaled S16
and an S32) shows the generic decoder's other kinds of value.
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from gcu_async.capture import PacketCapture
from gcu_async.protocol import (
    COMMAND_TYPES,
    Feedback,
    GcuMainFrame,
    GcuPacket,
    HostMainFrame,
    HostPacket,
    UnknownCommand,
)
from gcu_async.wireshark import tables, template_path
from gcu_async.wireshark.tables import WireParam, WireRow
from helpers.wireshark.tshark import Item, dissect, needs_tshark

pytestmark = needs_tshark

FREE = [op for op in range(0x82, 0x100) if op not in COMMAND_TYPES]
"""Opcodes V2.0.6 leaves free (a command added to the schema takes its opcode out)."""
DEFOG = WireRow(FREE[0], "EXAMPLE_DEFOG", (WireParam("level", "B", 1, "", 0, 2, None),))
HEATER = WireRow(FREE[1], "EXAMPLE_HEATER", (  # a wider one: a mask, a scaled S16, an S32
    WireParam("cameras", "B", 1, "", 1, 255, "CameraMask"),
    WireParam("target", "h", 10, "degC", -400, 850, None),
    WireParam("heading", "i", 1e7, "deg", None, None, None),
))  # fmt: skip
NAMED = [("EXAMPLE_DEFOG", "Command name: EXAMPLE_DEFOG")]
HOST, GCU = ("127.0.0.1", 2338), ("127.0.0.1", 2337)
PARAMS = [b"\x01", b"\x02", b"\x03", b"", b"\x01\x00"]
HEATER_PARAMS = [struct.pack("<Bhi", 2, -123, -1_234_567_891), struct.pack("<Bhi", 0, 851, 0)]


def write(path: Path) -> None:
    assert DEFOG.opcode not in COMMAND_TYPES  # the protocol package does not know it
    capture = PacketCapture(path)
    capture.acquire()
    rows = [(DEFOG.opcode, p) for p in PARAMS] + [(HEATER.opcode, p) for p in HEATER_PARAMS]
    for opcode, params in rows:
        command = UnknownCommand(opcode, params)
        capture.udp(HOST, GCU, HostPacket(HostMainFrame(), None, command).encode())
    capture.udp(GCU, HOST, GcuPacket(GcuMainFrame(), None, Feedback(DEFOG.opcode, 1)).encode())
    capture.release()


def shown(item: Item, name: str) -> list[tuple[str, str]]:
    return [(f.show, f.showname) for f in item.named(name)]


def test_a_new_row_is_dissected_with_its_name_and_value(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    template = template_path().read_bytes()
    path = tmp_path / "defog.pcapng"
    write(path)
    before = [f.items[0] for f in dissect(path)]  # today's rows: an opcode V2.0.6 lacks
    assert shown(before[0], "xfgcu.host.command.command") == [
        (f"UNKNOWN_0x{DEFOG.opcode:02X}", f"Command name: UNKNOWN_0x{DEFOG.opcode:02X}")
    ]
    assert not any(f.name.startswith("xfgcu.host.command.example_defog") for f in before[0].fields)

    real = tables.wire_rows()
    monkeypatch.setattr(tables, "wire_rows", lambda: (*real, DEFOG, HEATER))
    host = [f.items[0] for f in dissect(path)]
    feedback = host.pop()
    heater = [host.pop(), host.pop()][::-1]
    assert template_path().read_bytes() == template  # nothing checked in was touched

    for item in host:
        assert shown(item, "xfgcu.host.command.command") == NAMED
    assert shown(host[0], "xfgcu.host.command.example_defog.level") == [("1", "Level: 1")]
    assert shown(host[0], "xfgcu.host.command.params_raw") == [("1", "Raw: 1")]
    assert shown(host[1], "xfgcu.host.command.example_defog.level") == [("2", "Level: 2")]
    for item in host[:2]:
        assert not item.has("xfgcu.anomaly")
    assert shown(host[2], "xfgcu.host.command.example_defog.level") == [("3", "Level: 3")]
    assert [f.show for f in host[2].named("xfgcu.anomaly")] == [
        "level: 3 is outside the allowed range [0, 2]"
    ]
    assert host[2].has("xfgcu.anomaly.expert")
    for item, size in zip(host[3:], (0, 2), strict=True):
        assert not item.has("xfgcu.host.command.example_defog.level")
        assert [f.show for f in item.named("xfgcu.anomaly")] == [
            f"params: {size} is outside the allowed range [1, 1] bytes "
            "(EXAMPLE_DEFOG has 1 parameter bytes)"
        ]
    assert shown(feedback, "xfgcu.gcu.feedback.command") == NAMED
    assert shown(feedback, "xfgcu.gcu.feedback.status") == [("FAILED", "Result: FAILED")]

    first, second = heater
    assert shown(first, "xfgcu.host.command.command") == [("EXAMPLE_HEATER",
                                                           "Command name: EXAMPLE_HEATER")]
    assert shown(first, "xfgcu.host.command.example_heater.cameras") == [
        ("0x02", "Cameras: 0x02 (camera_2)")]
    assert shown(first, "xfgcu.host.command.example_heater.target") == [
        ("-12.3", "Target: -12.3 degC")]
    assert shown(first, "xfgcu.host.command.example_heater.heading") == [
        ("-123.4567891", "Heading: -123.4567891 deg")]
    assert [f.show for f in first.named("xfgcu.host.command.params_raw")] == [
        "2", "-123", "-1234567891"]
    assert not first.has("xfgcu.anomaly")
    assert [f.show for f in second.named("xfgcu.anomaly")] == [
        "cameras: 0 is outside the allowed range [1, 255]",
        "target: 851 is outside the allowed range [-400, 850] 0.1 degC"]
