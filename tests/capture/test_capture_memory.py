"""``gcu-async decode`` reads its input as a stream: bounded memory and time whatever it is.

Each case runs the real console script as a subprocess under a small measuring process that
reports the script's peak RSS (``getrusage(RUSAGE_CHILDREN).ru_maxrss``: its only child)
and wall time. The issue-17 figures on the old code: a 1 GiB sparse file peaked at 1,051
MiB, ``/dev/zero`` grew to 601 MiB in 0.5 s (and on), 21 MB of hex on stdin peaked at 615
MiB. The bound here is 100 MiB (the interpreter with the package imported is about 30).
"""

from __future__ import annotations

import json
import os
import shutil
import struct
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from gcu_async.capture.synth import udp_packet
from helpers.protocol.vectors import GCU_EXAMPLE, HOST_EXAMPLE

PEAK_MIB = 100
GIB = 1 << 30
TIMEOUT = 120.0  # a hang guard only; each case takes seconds

_MEASURE = """
import json, resource, subprocess, sys, time
argv, stdin = json.loads(sys.argv[1]), sys.argv[2]
start = time.monotonic()
with open(stdin, "rb") as source:
    proc = subprocess.run(argv, stdin=source, capture_output=True, timeout=float(sys.argv[3]))
peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss  # KiB on Linux
print(json.dumps({"status": proc.returncode, "stdout": proc.stdout.decode(),
                  "stderr": proc.stderr.decode(), "peak_mib": peak / 1024,
                  "seconds": time.monotonic() - start}))
"""


def _script() -> str:
    script = Path(sys.executable).with_name("gcu-async")
    if script.exists():
        return str(script)
    found = shutil.which("gcu-async")
    if found is None:
        pytest.fail("the gcu-async console script is not installed (pip install -e .)")
    return found


def measure(*args: str, stdin: str = os.devnull) -> dict[str, Any]:
    argv = [_script(), "decode", *args]
    proc = subprocess.run([sys.executable, "-c", _MEASURE, json.dumps(argv), stdin,
                           str(TIMEOUT)], capture_output=True, text=True, timeout=TIMEOUT + 10,
                          check=True)  # fmt: skip
    result: dict[str, Any] = json.loads(proc.stdout)
    assert result["peak_mib"] < PEAK_MIB, result
    assert "Traceback" not in result["stderr"]
    return result


def one_error_line(result: dict[str, Any]) -> str:
    lines = result["stderr"].splitlines()
    assert len(lines) == 1 and lines[0].startswith("gcu-async decode: "), lines
    return str(lines[0])


def packets_of(result: dict[str, Any]) -> list[dict[str, Any]]:
    return [json.loads(line) for line in result["stdout"].splitlines()]


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
def test_dev_zero_is_not_a_capture_and_ends_with_an_error() -> None:
    result = measure("--file", "/dev/zero")
    assert result["status"] == 1
    line = one_error_line(result)
    assert "offset 0 holds 00 00 00 00" in line and "not a GCU byte stream" in line


def test_a_1_gib_sparse_file_of_zeros(tmp_path: Path) -> None:
    path = tmp_path / "sparse.bin"
    with path.open("wb") as f:
        f.truncate(GIB)
    result = measure("--file", str(path))
    assert result["status"] == 1
    assert "offset 0 holds 00 00 00 00" in one_error_line(result)


def _pcapng_block(kind: int, body: bytes) -> bytes:
    body += b"\0" * (-len(body) % 4)
    length = len(body) + 12
    return struct.pack("<II", kind, length) + body + struct.pack("<I", length)


def _epb(data: bytes) -> bytes:
    return _pcapng_block(6, struct.pack("<IIIII", 0, 0, 0, len(data), len(data)) + data)


def test_a_1_gib_sparse_pcapng_with_a_huge_block_between_packets(tmp_path: Path) -> None:
    """A block of a type decode does not use (custom, 0x40000BAD) of 1 GiB between two
    packets: skipped without reading it into memory; both packets decode."""
    shb = _pcapng_block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    idb = _pcapng_block(1, struct.pack("<HHI", 101, 0, 0))
    first = _epb(udp_packet(("127.0.0.1", 1), ("127.0.0.2", 2), HOST_EXAMPLE))
    last = _epb(udp_packet(("127.0.0.2", 2), ("127.0.0.1", 1), GCU_EXAMPLE))
    huge = GIB
    path = tmp_path / "sparse.pcapng"
    with path.open("wb") as f:
        f.write(shb + idb + first + struct.pack("<II", 0x40000BAD, huge))
        f.seek(huge - 12, os.SEEK_CUR)
        f.write(struct.pack("<I", huge) + last)
    assert path.stat().st_size > GIB
    result = measure("--file", str(path))
    assert result["status"] == 0, result["stderr"]
    objs = packets_of(result)
    assert [o["capture"]["frame"] for o in objs] == [1, 2]
    assert [o["direction"] for o in objs] == ["host_to_gcu", "gcu_to_host"]


def test_a_raw_byte_stream_with_a_256_mib_gap_is_read_through(tmp_path: Path) -> None:
    path = tmp_path / "gap.bin"
    with path.open("wb") as f:
        f.write(GCU_EXAMPLE)
        f.seek(256 << 20, os.SEEK_CUR)
        f.write(HOST_EXAMPLE)
    result = measure("--file", str(path))
    assert result["status"] == 0, result["stderr"]
    assert [o["direction"] for o in packets_of(result)] == ["gcu_to_host", "host_to_gcu"]


def test_21_mb_of_hex_on_stdin_is_streamed(tmp_path: Path) -> None:
    path = tmp_path / "hex.txt"
    filler = "00 " * 1_000_000  # 3 MB of hex per block
    with path.open("w") as f:
        for _ in range(7):
            f.write(GCU_EXAMPLE.hex(" ") + "\n" + filler + "\n")
    assert path.stat().st_size > 21_000_000
    result = measure(stdin=str(path))
    assert result["status"] == 0, result["stderr"]
    assert len(packets_of(result)) == 7


def test_a_capture_through_a_pipe_with_a_256_mib_block(tmp_path: Path) -> None:
    """A device or pipe cannot seek: the block that is not used is read in chunks."""
    fifo = tmp_path / "capture.fifo"
    os.mkfifo(fifo)
    shb = _pcapng_block(0x0A0D0D0A, struct.pack("<IHHq", 0x1A2B3C4D, 1, 0, -1))
    idb = _pcapng_block(1, struct.pack("<HHI", 101, 0, 0))
    packet = _epb(udp_packet(("127.0.0.1", 1), ("127.0.0.2", 2), HOST_EXAMPLE))
    size = 256 << 20

    def write() -> None:
        with fifo.open("wb") as f:
            f.write(shb + idb + packet + struct.pack("<II", 0x40000BAD, size))
            zeros = bytes(1 << 20)
            for _ in range((size - 12) // len(zeros)):
                f.write(zeros)
            f.write(bytes((size - 12) % len(zeros)) + struct.pack("<I", size) + packet)

    writer = threading.Thread(target=write, daemon=True)
    writer.start()
    try:
        result = measure("--file", str(fifo))
    finally:
        writer.join(TIMEOUT)
    assert result["status"] == 0, result["stderr"]
    assert [o["capture"]["frame"] for o in packets_of(result)] == [1, 2]


def test_hex_from_a_live_pipe_is_decoded_before_the_pipe_ends() -> None:
    """Hex is decoded as it arrives: a packet is out while stdin is still open, once the
    bytes after it show it is not the start of a longer one (fewer than 256 bytes later:
    the deframer's hold-back bound, docs/cli.md)."""
    with subprocess.Popen([_script(), "decode"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE) as proc:  # fmt: skip
        try:
            assert proc.stdin is not None and proc.stdout is not None
            proc.stdin.write((GCU_EXAMPLE * 4).hex(" ").encode() + b"\n")
            proc.stdin.flush()
            line = _readline_within(proc.stdout, TIMEOUT)
            assert json.loads(line)["direction"] == "gcu_to_host"
            assert proc.poll() is None  # still reading
            proc.stdin.close()
            assert proc.wait(TIMEOUT) == 0
        finally:
            if proc.poll() is None:
                proc.kill()


def _readline_within(stream: Any, seconds: float) -> bytes:
    got: list[bytes] = []
    reader = threading.Thread(target=lambda: got.append(stream.readline()), daemon=True)
    reader.start()
    reader.join(seconds)
    assert got, f"no output within {seconds} s"
    return got[0]
