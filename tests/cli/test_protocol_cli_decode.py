"""``gcu-async decode`` through the real console script: hex arguments, hex on stdin in loose
formats, binary captures with junk around packets of both directions; JSON lines with
direction, opcode name, execution status and unit + raw fields; exit 1 with a one-line reason
when there is no valid packet."""

from __future__ import annotations

import itertools
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from gcu_async.cli import decode as decode_cli
from gcu_async.protocol import (
    Feedback,
    GcuMainFrame,
    GcuPacket,
    HostMainFrame,
    HostPacket,
    Opcode,
    Palette,
    ZoomTo,
)
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE
from helpers.scale import scaled


def _entry_point() -> list[str]:
    script = Path(sys.executable).with_name("gcu-async")
    if script.exists():
        return [str(script)]
    found = shutil.which("gcu-async")
    if found is None:
        pytest.fail("the gcu-async console script is not installed (pip install -e .)")
    return [found]


def run_cli(*args: str, stdin: str | bytes | None = None) -> subprocess.CompletedProcess[str]:
    data = stdin.decode() if isinstance(stdin, bytes) else stdin
    return subprocess.run(
        [*_entry_point(), "decode", *args],
        input=data if data is not None else "",
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )


def json_lines(out: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in out.splitlines() if line.strip()]


def assert_one_line_failure(proc: subprocess.CompletedProcess[str], reason: str,
                            status: int = 1) -> None:  # fmt: skip
    """1: nothing decodable; 2: a usage error (not hex, no such file)."""
    assert proc.returncode == status
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith("gcu-async decode: ")
    assert reason in lines[0]
    assert "Traceback" not in proc.stderr


def check_gcu_example(obj: dict[str, Any]) -> None:
    assert obj["direction"] == "gcu_to_host"
    assert obj["version"] == 2
    assert obj["feedback"] == {
        "command": "TAKE_PHOTO",
        "opcode": 0x20,
        "status": "SUCCESS",
        "status_raw": 0,
        "failed_cameras": 0,
    }
    main, sub = obj["main"], obj["sub"]
    assert (main["mode"], main["mode_raw"]) == ("POINTING_FOLLOW", 0x12)
    assert main["pod_status_raw"] == 0x8001
    assert main["pod_status"] == ["TRACKING_OK"]
    assert main["attitude_deg"] == {"roll": -0.01, "pitch": 9.33, "yaw": 62.15}
    assert main["attitude_raw"] == [-1, 933, 6215]
    assert main["relative_angles_deg"] == {"x": -8.03, "y": 0.32, "z": 62.18}
    assert (sub["pod_model"], sub["pod_code"]) == ("D-90AI", 41)  # the vendor's name
    assert (sub["target_distance_m"], sub["target_distance_raw"]) == (589.4, 5894)
    assert (sub["camera1_zoom"], sub["camera1_zoom_raw"]) == (29.9, 299)
    assert sub["time_zone"] == 8


def check_host_example(obj: dict[str, Any]) -> None:
    assert obj["direction"] == "host_to_gcu"
    assert obj["command"]["command"] == "NULL"
    assert obj["command"]["opcode"] == 0
    main, sub = obj["main"], obj["sub"]
    assert main["aircraft_attitude_deg"] == {"roll": -11.32, "pitch": 1.01, "yaw": 240.0}
    assert main["aircraft_attitude_raw"] == [-1132, 101, 24000]
    assert main["control_raw"] == [0, 100, -100]
    assert (sub["latitude_raw"], sub["longitude_raw"]) == (380300822, 1709175332)
    assert sub["gnss_time_utc"] == "2023-09-07T01:58:20+00:00"  # GPS time: 18 leap seconds
    assert sub["gnss_time_document_rule"] == "2023-09-07T01:58:38+00:00"  # the document's


def test_hex_on_the_command_line() -> None:
    proc = run_cli(*GCU_EXAMPLE.hex(" ").split())
    assert proc.returncode == 0, proc.stderr
    [obj] = json_lines(proc.stdout)
    check_gcu_example(obj)
    # one argument of unbroken hex works too
    assert json_lines(run_cli(HOST_EXAMPLE.hex()).stdout)[0]["direction"] == "host_to_gcu"


def test_hex_on_stdin_with_prefixes_commas_and_newlines() -> None:
    def loose(data: bytes) -> str:
        tokens = [f"0x{b:02X}" if i % 3 else f"{b:02x}" for i, b in enumerate(data)]
        return "\n".join(", ".join(tokens[i : i + 16]) for i in range(0, len(tokens), 16))

    proc = run_cli(stdin=loose(HOST_EXAMPLE) + ",\n\n" + loose(GCU_EXAMPLE) + "\n")
    assert proc.returncode == 0, proc.stderr
    host, gcu = json_lines(proc.stdout)  # stream order
    check_host_example(host)
    check_gcu_example(gcu)


def test_binary_capture_with_junk_both_directions(tmp_path: Path) -> None:
    zoom = HostPacket(HostMainFrame(), None, ZoomTo(ratio=10.0)).encode()
    zoom_failed = GcuPacket(GcuMainFrame(), None, Feedback(Opcode.ZOOM_TO, 0x02)).encode()
    palette = HostPacket(HostMainFrame(), None, Palette(3)).encode()
    calibrating = GcuPacket(GcuMainFrame(), None, Feedback(Opcode.CALIBRATION, 0x02)).encode()
    no_status = GcuPacket(GcuMainFrame(), None, Feedback(Opcode.NULL)).encode()
    capture = (
        b"\x00\xff\x8a"
        + HOST_EXAMPLE
        + b"\xa8\xe5\x10\x00junk"
        + GCU_EXAMPLE
        + zoom[:30]
        + b"\x8a\x5e"
        + zoom
        + zoom_failed
        + b"\x01\x02"
        + palette
        + calibrating
        + no_status
        + b"\xa8"
    )
    path = tmp_path / "capture.bin"
    path.write_bytes(capture)
    proc = run_cli("--file", str(path))
    assert proc.returncode == 0, proc.stderr
    objs = json_lines(proc.stdout)
    assert [o["direction"] for o in objs] == [
        "host_to_gcu",
        "gcu_to_host",
        "host_to_gcu",
        "gcu_to_host",
        "host_to_gcu",
        "gcu_to_host",
        "gcu_to_host",
    ]
    check_host_example(objs[0])
    check_gcu_example(objs[1])
    cmd = objs[2]["command"]
    assert cmd["command"] == "ZOOM_TO"
    assert cmd["opcode"] == 0x25
    assert cmd["params"]["ratio"] == 10.0
    assert cmd["params_raw"] == [1, -100]
    assert objs[3]["feedback"] == {
        "command": "ZOOM_TO",
        "opcode": 0x25,
        "status": "FAILED",
        "status_raw": 2,
        "failed_cameras": 2,
    }
    assert objs[4]["command"]["command"] == "PALETTE"
    assert objs[4]["command"]["params"] == {"palette": 3, "cameras": 2}
    assert objs[5]["feedback"]["status"] == "IN_PROGRESS"
    assert objs[6]["feedback"]["status"] == "NONE"
    assert objs[6]["feedback"]["status_raw"] is None


def test_indent_pretty_prints() -> None:
    proc = run_cli("--indent", "2", GCU_EXAMPLE.hex())
    assert proc.returncode == 0
    assert json.loads(proc.stdout)["feedback"]["command"] == "TAKE_PHOTO"
    assert proc.stdout.count("\n") > 20


@pytest.mark.parametrize(
    ("args", "stdin", "reason"),
    [
        (["00", "11", "22", "8a", "5e"], None, "no valid packet in 5 bytes"),
        ([], "", "no valid packet in 0 bytes"),
        ([], "\n  \n", "no valid packet in 0 bytes"),
        ([GCU_EXAMPLE[:-1].hex()], None, "no valid packet in 72 bytes"),
        ([(GCU_EXAMPLE[:-1] + b"\x00").hex()], None, "no valid packet in 73 bytes"),  # bad CRC
    ],
)
def test_no_valid_packet_exits_1_with_one_line(
    args: list[str], stdin: str | None, reason: str
) -> None:
    proc = run_cli(*args, stdin=stdin)
    assert_one_line_failure(proc, reason)
    assert proc.stdout == ""


@pytest.mark.parametrize(("args", "stdin", "reason"), [
    (["zz", "00"], None, "not hex: 'zz'"),
    ([], "8a 5e 49 0g", "not hex: '0g'"),
])  # fmt: skip
def test_input_that_is_not_hex_is_a_usage_error(args: list[str], stdin: str | None,
                                                reason: str) -> None:  # fmt: skip
    proc = run_cli(*args, stdin=stdin)
    assert_one_line_failure(proc, reason, status=2)
    assert proc.stdout == ""


def test_missing_file_is_a_usage_error(tmp_path: Path) -> None:
    assert_one_line_failure(run_cli("--file", str(tmp_path / "nope.bin")), "nope.bin", 2)


def test_garbage_file_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "noise.bin"
    path.write_bytes(bytes(range(256)) * 4)
    assert_one_line_failure(run_cli("--file", str(path)), "no valid packet in 1024 bytes")


def test_anomalous_packets_decode_flagged_and_exit_0() -> None:
    """Liberal receive (docs/client.md, "Liberal receive, strict send"): a version-3 reply
    and a time zone of +15 decode, flagged in the JSON and on stderr; exit status 0."""
    v3 = GcuPacket(GcuMainFrame(), version=3).encode()
    tz15 = _seal_host(HostPacket(HostMainFrame()).encode()[:69] + b"\x08\x0f")
    proc = run_cli(v3.hex() + tz15.hex())
    assert proc.returncode == 0, proc.stderr
    gcu, host = json_lines(proc.stdout)
    assert gcu["version"] == 3
    assert [(a["field"], a["value"], a["low"], a["high"]) for a in gcu["anomalies"]] == [
        ("version", 3, 1, 2)
    ]
    assert host["command"]["command"] == "TIME_ZONE"
    assert host["command"]["params_raw"] == [15]
    [anomaly] = host["anomalies"]
    assert (anomaly["field"], anomaly["value"], anomaly["low"], anomaly["high"]) == (
        "offset_hours", 15, -12, 14)
    lines = proc.stderr.splitlines()
    assert lines == [
        "gcu-async decode: packet 1 (gcu_to_host): flagged: version: 3 is outside the allowed "
        "range [1, 2] (V2.0.6 defines versions 1 and 2; decoded with its layout)",
        "gcu-async decode: packet 2 (host_to_gcu): flagged: offset_hours: 15 is outside the "
        "allowed range [-12, 14] h",
    ]


def _seal_host(head: bytes) -> bytes:
    from helpers.protocol.strategies import seal

    return seal(head[:2], head[5:])


def test_decode_into_a_closed_pipe_exits_quietly() -> None:
    import subprocess
    import sys

    hex_text = (GCU_EXAMPLE.hex(" ") + "\n") * 200
    proc = subprocess.run(
        f"{sys.executable} -m gcu_async.cli decode | head -c 10",
        shell=True,
        input=hex_text,
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )
    assert "Traceback" not in proc.stderr
    assert "BrokenPipeError" not in proc.stderr


def test_a_packet_inside_a_false_headers_span_at_the_end_is_still_decoded() -> None:
    """A false header claiming 80 bytes right before the last packet: at the end of the
    input its span can never complete, so the packet inside it is found (Deframer.flush)."""
    from gcu_async.cli.decode import decode_stream

    objects, _ = decode_stream(bytes.fromhex("8a5e5000") + GCU_EXAMPLE)
    assert len(objects) == 1 and objects[0]["feedback"]["command"] == "TAKE_PHOTO"


def test_the_simulator_answers_a_packet_inside_a_false_headers_span_in_a_datagram() -> None:
    from gcu_async.protocol import Deframer
    from gcu_async.sim import SimulatorModel

    model = SimulatorModel()
    packets = model.split(bytes.fromhex("a8e55000") + HOST_EXAMPLE, Deframer.for_host_packets(),
                          end=True)  # fmt: skip
    assert packets == [HOST_EXAMPLE]


def _whole_text_parse(text: str) -> bytes:
    """The reference: the whole text at once, token by token (a one-digit token is 0X)."""
    out = bytearray()
    for token in re.sub(r"0x|[\s,;:]+", " ", text, flags=re.IGNORECASE).split():
        out += bytes.fromhex("0" + token if len(token) == 1 else token)
    return bytes(out)


@settings(max_examples=scaled(300, 30), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(tokens=st.lists(st.sampled_from(["8a", "5E", "0x49", "0X0", "f", "abcd", "0", "x", "7",
                                         " ", ",", ";", ":", "\n", "\t", "  ", "0x"]),
                       max_size=60),
       cuts=st.lists(st.integers(0, 400), max_size=8), hold=st.integers(2, 9))  # fmt: skip
def test_hex_in_pieces_reads_as_the_whole_text(
    tokens: list[str], cuts: list[int], hold: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """However stdin splits the text (and however short the hold for one long token), the
    bytes, or the error, are those of the whole text."""
    monkeypatch.setattr(decode_cli, "HEX_TOKEN_HOLD", hold)
    text = "".join(tokens)
    bounds = sorted({min(c, len(text)) for c in cuts} | {0, len(text)})
    pieces = [text[a:b] for a, b in itertools.pairwise(bounds)]
    try:
        want: bytes | None = _whole_text_parse(text)
    except ValueError:
        want = None
    error = ""
    try:
        got: bytes | None = b"".join(decode_cli.iter_hex(pieces))
    except ValueError as exc:
        error, got = str(exc), None
    assert got == want
    assert got is not None or error.startswith("not hex: ")


@pytest.mark.skipif(sys.platform == "win32", reason="a pty")
def test_hex_typed_at_a_terminal_is_announced_then_decoded() -> None:
    """``gcu-async decode`` with no argument at a terminal says it reads the terminal and
    how to end (it would wait silently otherwise); a pipe gets no such line."""
    import os
    import pty

    master, slave = pty.openpty()
    try:
        proc = subprocess.Popen([*_entry_point(), "decode"], stdin=slave, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)  # fmt: skip
        os.close(slave)
        os.write(master, GCU_EXAMPLE.hex(" ").encode() + b"\n\x04")  # a line, then Ctrl-D
        out, err = proc.communicate(timeout=30)
    finally:
        os.close(master)
    assert proc.returncode == 0, err
    assert err.splitlines()[0] == decode_cli.TERMINAL_HINT
    assert json.loads(out.splitlines()[0])["direction"] == "gcu_to_host"
    piped = run_cli(stdin=GCU_EXAMPLE.hex())
    assert piped.returncode == 0 and decode_cli.TERMINAL_HINT not in piped.stderr
