"""``gcu-async decode``: hex, a raw binary capture or a pcap/pcapng capture in, one JSON
object per packet out.

Every packet that frames (header, length, CRC) decodes: values V2.0.6 does not expect are
shown as an ``anomalies`` list in its JSON object and one line each on stderr, and do not
change the exit status (docs/client.md, "Liberal receive, strict send")."""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

from gcu_async.capture.reader import is_capture
from gcu_async.cli._exit import EXIT_FAILED, EXIT_OK, EXIT_USAGE
from gcu_async.protocol.deframer import Deframer
from gcu_async.protocol.packets import (
    GCU_HEADER,
    HOST_HEADER,
    decode_gcu_packet,
    decode_host_packet,
)

_HEX_TOKEN = re.compile(r"0x|[\s,;:]+", re.IGNORECASE)


def register(sub: Any) -> None:
    p = sub.add_parser(
        "decode",
        help="decode packets from hex or a binary capture to JSON lines",
        description="Decode GCU protocol packets of both directions. Hex comes from the "
        "arguments or, with none, from stdin; whitespace, 0x prefixes and commas are ignored.",
    )
    p.add_argument("hex", nargs="*", help="hex bytes (default: read stdin)")
    p.add_argument(
        "--file",
        type=Path,
        help="decode this file instead of hex: a pcap or pcapng capture (UDP, TCP, gcu_async's "
        "serial link type; needs the 'capture' extra) or raw bytes",
    )
    p.add_argument("--indent", type=int, default=None, help="pretty-print JSON with this indent")
    p.set_defaults(run=run)


def parse_hex(text: str) -> bytes:
    """Bytes from hex text; tolerates any whitespace, ``0x`` prefixes, commas, colons."""
    digits = _HEX_TOKEN.sub(" ", text).split()
    out = bytearray()
    for token in digits:
        if len(token) % 2:
            token = "0" + token if len(token) == 1 else token
        try:
            out += bytes.fromhex(token)
        except ValueError:
            raise ValueError(f"not hex: {token!r}") from None
    return bytes(out)


def decode_spans(data: bytes) -> list[tuple[int, int, dict[str, Any]]]:
    """Every packet of both directions in ``data`` as (offset, length, JSON object), in
    stream order: one deframer per direction reads the whole of ``data`` and is flushed at
    its end (a datagram, or a stream that ended)."""
    found: list[tuple[int, int, dict[str, Any]]] = []
    for header, decoder in ((GCU_HEADER, decode_gcu_packet), (HOST_HEADER, decode_host_packet)):
        deframer = Deframer(header)
        offset = 0
        for raw in [*deframer.feed(data), *deframer.flush()]:
            offset = data.find(raw, offset)
            # the deframer checked header, length and CRC: nothing else makes decode raise
            found.append((offset, len(raw), decoder(raw).as_dict()))
            offset += len(raw)
    found.sort(key=lambda item: item[0])
    return found


def decode_stream(data: bytes) -> tuple[list[dict[str, Any]], dict[str, int]]:
    """Decode every packet of both directions in ``data``, in stream order; the counts say
    how many packets there are and how many of them carry anomalies."""
    spans = decode_spans(data)
    flagged = sum(1 for _, _, obj in spans if "anomalies" in obj)
    return [obj for _, _, obj in spans], {"packets": len(spans), "flagged": flagged}


def decode_capture(data: bytes) -> list[dict[str, Any]]:
    """Every packet of a pcap or pcapng capture, each with a ``capture`` object: the
    ``frame`` (1-based, as in Wireshark) that brought its last byte, its ``link`` (udp, tcp,
    serial), ``src`` and ``dst``, and the ``stream`` it belongs to. UDP datagrams are
    decoded one by one; the bytes of each TCP or serial direction are put in order first.
    Ordered by frame, then by position. Raises ``ValueError`` for a damaged file and
    :class:`~gcu_async.capture.CaptureUnavailable` without the ``capture`` extra."""
    from gcu_async.capture.reader import read_records
    from gcu_async.capture.reassembly import units

    found: list[tuple[int, int, int, dict[str, Any]]] = []
    for number, unit in enumerate(units(read_records(data))):
        for offset, length, obj in decode_spans(bytes(unit.data)):
            frame = unit.frame_of(offset + length - 1)
            where = {"frame": frame, "link": unit.link, "src": unit.src, "dst": unit.dst,
                     "stream": unit.name}  # fmt: skip
            found.append((frame, number, offset, {**obj, "capture": where}))
    found.sort(key=lambda item: item[:3])
    return [obj for *_, obj in found]


def _silence_stdout() -> None:
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def _report_anomalies(number: int, obj: dict[str, Any]) -> None:
    """One stderr line per anomaly of packet ``number`` (1-based, in output order)."""
    for anomaly in obj.get("anomalies", ()):
        print(f"gcu-async decode: packet {number} ({obj['direction']}): flagged: "
              f"{anomaly['message']}", file=sys.stderr)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    try:
        if args.file is not None:
            data = args.file.read_bytes()
        else:
            text = " ".join(args.hex) if args.hex else sys.stdin.read()
            data = parse_hex(text)
        if args.file is not None and is_capture(data):
            packets = decode_capture(data)
        else:
            packets, _ = decode_stream(data)
    except ImportError as exc:  # a capture file without the capture extra
        print(f"gcu-async decode: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except (OSError, ValueError) as exc:  # unreadable file, not hex: a usage error
        print(f"gcu-async decode: {exc}", file=sys.stderr)
        return EXIT_USAGE
    try:
        for number, obj in enumerate(packets, 1):
            print(json.dumps(obj, indent=args.indent))
            _report_anomalies(number, obj)
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into `head`: the reader has all it wants
        _silence_stdout()
        return EXIT_OK if packets else EXIT_FAILED
    if not packets:
        print(f"gcu-async decode: no valid packet in {len(data)} bytes of input", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK
