"""``gcu-async decode``: hex or a binary capture in, one JSON object per packet out."""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

from gcu_async.cli._exit import EXIT_FAILED, EXIT_OK, EXIT_USAGE
from gcu_async.errors import RemoteProtocolError
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
    p.add_argument("--file", type=Path, help="binary capture file to decode instead of hex")
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


def decode_stream(data: bytes) -> tuple[list[dict[str, Any]], dict[str, int]]:
    """Decode every packet of both directions in ``data``, in stream order."""
    found: list[tuple[int, dict[str, Any]]] = []
    errors = 0
    for header, decoder in ((GCU_HEADER, decode_gcu_packet), (HOST_HEADER, decode_host_packet)):
        deframer = Deframer(header)
        offset = 0
        for raw in [*deframer.feed(data), *deframer.flush()]:
            offset = data.find(raw, offset)
            try:
                found.append((offset, decoder(raw).as_dict()))
            except RemoteProtocolError as exc:
                errors += 1
                found.append((offset, {"error": str(exc), "hex": raw.hex(" ")}))
            offset += len(raw)
    found.sort(key=lambda item: item[0])
    return [obj for _, obj in found], {"decode_errors": errors}


def _silence_stdout() -> None:
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def run(args: argparse.Namespace) -> int:
    try:
        if args.file is not None:
            data = args.file.read_bytes()
        else:
            text = " ".join(args.hex) if args.hex else sys.stdin.read()
            data = parse_hex(text)
    except (OSError, ValueError) as exc:  # unreadable file, not hex: a usage error
        print(f"gcu-async decode: {exc}", file=sys.stderr)
        return EXIT_USAGE
    packets, _ = decode_stream(data)
    valid = [p for p in packets if "error" not in p]
    try:
        for obj in packets:
            print(json.dumps(obj, indent=args.indent))
        sys.stdout.flush()
    except BrokenPipeError:  # e.g. piped into `head`: the reader has all it wants
        _silence_stdout()
        return EXIT_OK if valid else EXIT_FAILED
    if not valid:
        print(f"gcu-async decode: no valid packet in {len(data)} bytes of input", file=sys.stderr)
        return EXIT_FAILED
    return EXIT_OK
