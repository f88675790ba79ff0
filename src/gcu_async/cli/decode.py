"""``gcu-async decode``: hex, a raw binary capture or a pcap/pcapng capture in, one JSON
object per packet out, read as a stream (bounded memory whatever the input; docs/cli.md,
"Input read as a stream").

Every packet that frames (header, length, CRC) decodes: values V2.0.6 does not expect are
shown as an ``anomalies`` list in its JSON object and do not change the exit status
(docs/client.md, "Liberal receive, strict send"). Stderr says each kind of anomaly (its
direction, field and detail) once, at the first packet that has it, and at the end how many
packets had each kind that came more than once. ``--report FILE`` writes the conformance
report of the GCU packets in the input, and of its host packets when there are any
(docs/conformance.md)."""

from __future__ import annotations

import argparse
import io
import json
import re
import sys
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any, BinaryIO, TextIO

from gcu_async.capture.blocks import CaptureError, Source
from gcu_async.capture.reader import is_capture
from gcu_async.capture.scan import PacketScanner, Rejection
from gcu_async.cli._exit import (
    EXIT_FAILED,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    missing_extra,
    silence_stdout,
)
from gcu_async.cli._report import GCU_REPORT_HELP, add_report_option, write_report
from gcu_async.conformance import GcuConformance, HostConformance
from gcu_async.protocol.command_decode import command_code
from gcu_async.protocol.packets import GcuPacket

_HEX_TOKEN = re.compile(r"0x|[\s,;:]+", re.IGNORECASE)
CHUNK = 1 << 16
"""Bytes (or hex characters) read at a time."""
HEX_TOKEN_HOLD = 1 << 16
"""Hex digits without a separator held before their whole pairs are parsed."""
RAW_PROBE = 1 << 20
"""A file that is not a capture and holds no packet in this many bytes is not a GCU byte
stream: an error (``/dev/zero``, a sparse file), not a read to its end."""
MAX_KINDS = 1000
"""Kinds of anomaly stderr remembers having shown; past that, new kinds are shown at every
packet (never dropped)."""


TERMINAL_HINT = ("gcu-async decode: reading hex from the terminal, decoded line by line; end "
                 "with Ctrl-D (or give the hex as arguments, or --file FILE)")  # fmt: skip
"""Said when stdin is a terminal: otherwise ``decode`` without arguments would wait
silently."""


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
        "serial link type; needs the 'capture' extra) or raw bytes; a pipe or device is read "
        "as it comes",
    )
    p.add_argument("--indent", type=int, default=None, help="pretty-print JSON with this indent")
    add_report_option(p, f"{GCU_REPORT_HELP}: of the GCU packets in the input, and the host "
                      "conformance report of its host packets after it when there are any; "
                      "a capture's times time them (hex and raw bytes have none)")  # fmt: skip
    p.set_defaults(run=run)


def parse_hex(text: str) -> bytes:
    """Bytes from hex text; tolerates any whitespace, ``0x`` prefixes, commas, colons."""
    return b"".join(iter_hex([text]))


def iter_hex(chunks: Iterable[str]) -> Iterator[bytes]:
    """Bytes from hex text that comes in pieces (stdin), as it comes: what :func:`parse_hex`
    reads from the whole text, whatever the split, holding at most one piece plus
    :data:`HEX_TOKEN_HOLD` characters. ``ValueError`` names the first token that is not hex
    and the character offset it starts at."""
    carry, base = "", 0  # text not yet parsed, and the offset of its first character
    continued = False  # carry goes on a token whose first digits were parsed already
    for chunk in chunks:
        text = carry + chunk
        cut = _last_separator_end(text)
        if cut:
            yield _hex_bytes(text[:cut], base, continued)
            continued = False
        elif len(text) > HEX_TOKEN_HOLD:  # one long token: parse its whole pairs
            cut = len(text) - 2 + len(text) % 2  # keep the last digit(s): "0" may begin "0x"
            yield _hex_bytes(text[:cut], base, continued)
            continued = True
        carry, base = text[cut:], base + cut
    if carry:
        yield _hex_bytes(carry, base, continued)


def _last_separator_end(text: str) -> int:
    """Where the text after the last separator starts (0: no separator)."""
    end = 0
    for match in _HEX_TOKEN.finditer(text):
        end = match.end()
    return end


def _hex_bytes(text: str, base: int, continued: bool) -> bytes:
    """The bytes of ``text`` (``continued``: its first token goes on an earlier one)."""
    try:  # fast path: bytes.fromhex skips the spaces between whole pairs, and fails on
        return bytes.fromhex(_HEX_TOKEN.sub(" ", text))  # any odd-length token
    except ValueError:
        pass  # a one-digit token (read as 0X), or not hex: token by token
    out = bytearray()
    pos = 0
    for match in [*_HEX_TOKEN.finditer(text), None]:
        stop = match.start() if match else len(text)
        token = text[pos:stop]
        if token:
            if len(token) == 1 and not (continued and pos == 0):
                token = "0" + token
            try:
                out += bytes.fromhex(token)
            except ValueError:
                shown = token if len(token) <= 40 else token[:40] + "..."
                raise ValueError(f"not hex: {shown!r} at character {base + pos}") from None
        if match:
            pos = match.end()
    return bytes(out)


def decode_spans(data: bytes) -> list[tuple[int, int, dict[str, Any]]]:
    """Every packet of both directions in ``data`` as (offset, length, JSON object), in
    stream order: one deframer per direction reads the whole of ``data`` and is flushed at
    its end (a datagram, or a stream that ended)."""
    scanner = PacketScanner()
    return [*scanner.feed(data), *scanner.flush()]


def decode_stream(data: bytes) -> tuple[list[dict[str, Any]], dict[str, int]]:
    """Decode every packet of both directions in ``data``, in stream order; the counts say
    how many packets there are and how many of them carry anomalies."""
    spans = decode_spans(data)
    flagged = sum(1 for _, _, obj in spans if "anomalies" in obj)
    return [obj for _, _, obj in spans], {"packets": len(spans), "flagged": flagged}


def decode_capture(data: bytes | BinaryIO) -> list[dict[str, Any]]:
    """Every packet of a pcap or pcapng capture (bytes or a binary stream), each with a
    ``capture`` object (see :mod:`gcu_async.capture.decoding`). Raises
    :class:`~gcu_async.capture.CaptureError` (a ``ValueError``) for a damaged file and
    :class:`~gcu_async.capture.CaptureUnavailable` without the ``capture`` extra."""
    from gcu_async.capture.decoding import CaptureDecoder

    stream = io.BytesIO(bytes(data)) if isinstance(data, (bytes, bytearray)) else data
    return list(CaptureDecoder(Source(stream)))


class _Failure(Exception):
    """Ends the run with one line on stderr and this exit status."""

    def __init__(self, message: str, status: int = EXIT_FAILED) -> None:
        super().__init__(message)
        self.status = status


class _Output:
    """Prints each packet as it is found: one JSON line (stdout); each kind of anomaly once
    (stderr), counted; feeds the conformance reports (``--report``)."""

    def __init__(self, indent: int | None, reports: _Reports | None = None) -> None:
        self.indent = indent
        self.count = 0
        self.reports = reports
        self.kinds: dict[tuple[str, str, str], list[int]] = {}
        """(direction, field, detail) → [its first packet, packets with it]."""

    def __call__(self, obj: dict[str, Any]) -> None:
        self.count += 1
        sys.stdout.write(json.dumps(obj, indent=self.indent) + "\n")
        sys.stdout.flush()  # a live pipe or device: each packet as soon as it is read
        if self.reports is not None:
            self.reports.add(obj)
        kinds = self.kinds
        for anomaly in obj.get("anomalies", ()):
            key = (obj["direction"], anomaly["field"], anomaly["detail"])
            seen = kinds.get(key)
            if seen is not None:
                seen[1] += 1
                continue
            if len(kinds) < MAX_KINDS:
                kinds[key] = [self.count, 1]
            print(f"gcu-async decode: packet {self.count} ({obj['direction']}): flagged: "
                  f"{anomaly['message']}", file=sys.stderr)  # fmt: skip

    def summary(self) -> None:
        """One stderr line per kind of anomaly more than one packet had."""
        for (direction, field, _), (first, n) in self.kinds.items():
            if n > 1:
                print(f"gcu-async decode: {n} packets ({direction}): flagged: {field}, "
                      f"shown once, at packet {first}", file=sys.stderr)  # fmt: skip


class _Reports:
    """The conformance reports of ``--report``: the GCU's, and the host's when the input has
    host packets. Times from the capture, when there is one."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.gcu = GcuConformance()
        self.host = HostConformance()
        self.timed = True

    def add(self, obj: dict[str, Any]) -> None:
        raw: bytes = getattr(obj, "raw", b"")
        packet = getattr(obj, "packet", None)
        capture = obj.get("capture")
        time = capture["time"] if capture is not None else None
        self.timed = self.timed and time is not None
        if isinstance(packet, GcuPacket):
            self.gcu.add_packet(packet, time, raw=raw)
        elif packet is not None:
            self.host.add_packet(packet, time if time is not None else 0.0, raw=raw)
            self.gcu.host_sent(command_code(packet.command), time)

    def write(self) -> None:
        parts = []
        if not self.timed:
            parts.append("The input has no times (hex or raw bytes): rates, silences and "
                         "feedback timing are not measured.")  # fmt: skip
        parts.append(self.gcu.report().text())
        if self.host.packets:
            parts.append(self.host.report().text())
        try:
            write_report(self.path, "\n\n".join(parts) + "\n")
        except OSError as exc:
            print(f"gcu-async decode: cannot write the report: {exc}", file=sys.stderr)


def _why(rejection: Rejection | None, stream: str | None = None) -> str:
    if rejection is None:
        return ""
    where = f" of {stream}" if stream else ""
    return f": {rejection.message}{where}"


def _scan_bytes(chunks: Iterable[bytes], output: _Output, *, probe: int | None = None,
                what: str = "input") -> int:  # fmt: skip
    """Decode a raw byte stream as it comes; returns the bytes read. With ``probe``, give up
    (an error) when its first ``probe`` bytes hold no packet: not a GCU byte stream."""
    scanner = PacketScanner(keep=output.reports is not None)
    for chunk in chunks:
        for _, _, obj in scanner.feed(chunk):
            output(obj)
        if probe is not None and not output.count and scanner.fed >= probe:
            why = _why(scanner.rejection)
            raise _Failure(f"{what}: no valid packet in its first {scanner.fed} bytes, so not "
                           f"a GCU byte stream{why}; stopped reading")  # fmt: skip
    for _, _, obj in scanner.flush():
        output(obj)
    if not output.count:
        raise _Failure(f"no valid packet in {scanner.fed} bytes of {what}"
                       f"{_why(scanner.rejection)}")  # fmt: skip
    return scanner.fed


def _read_chunks(stream: BinaryIO, head: bytes) -> Iterator[bytes]:
    """What the file has, as it comes (a device or pipe: what it has now, not a full chunk)."""
    if head:
        yield head
    read = getattr(stream, "read1", stream.read)
    while chunk := read(CHUNK):
        yield chunk


def _text_chunks(stream: TextIO) -> Iterator[str]:
    """Lines of at most CHUNK characters, so that a live pipe is decoded line by line."""
    while chunk := stream.readline(CHUNK):
        yield chunk


def _decode_file(path: Path, output: _Output) -> None:
    try:
        stream = path.open("rb")
    except OSError as exc:  # no such file, a directory, no permission: a usage error
        raise _Failure(str(exc), EXIT_USAGE) from None
    with stream:
        head = stream.read(4)
        if not is_capture(head):
            shown = head.hex(" ") or "nothing"
            what = f"{path} (not a pcap or pcapng file: offset 0 holds {shown})"
            _scan_bytes(_read_chunks(stream, head), output, probe=RAW_PROBE, what=what)
            return
        from gcu_async.capture.decoding import CaptureDecoder

        decoder = CaptureDecoder(Source(stream, head), keep=output.reports is not None)
        try:
            for obj in decoder:
                output(obj)
        except CaptureError as exc:
            raise _Failure(f"{path}: damaged capture after {output.count} packets: {exc}") from None
        if not output.count:
            stream_name, rejection = decoder.rejection or (None, None)
            raise _Failure(f"{path}: no valid packet in {decoder.bytes_read} bytes of capture"
                           f"{_why(rejection, stream_name)}")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    reports = _Reports(args.report) if args.report is not None else None
    output = _Output(args.indent, reports)
    try:
        return _run(args, output)
    finally:
        output.summary()
        if reports is not None and output.count:
            reports.write()


def _run(args: argparse.Namespace, output: _Output) -> int:
    try:
        if args.file is not None:
            _decode_file(args.file, output)
        else:
            if not args.hex and sys.stdin.isatty():  # a new user's `gcu-async decode`
                print(TERMINAL_HINT, file=sys.stderr, flush=True)
            text = [" ".join(args.hex)] if args.hex else _text_chunks(sys.stdin)
            _scan_bytes(iter_hex(text), output)
        sys.stdout.flush()
    except KeyboardInterrupt:  # Ctrl-C while reading a device or a pipe
        return _fail("interrupted", EXIT_INTERRUPTED)
    except BrokenPipeError:  # e.g. piped into `head`: the reader has all it wants
        silence_stdout()
        return EXIT_OK if output.count else EXIT_FAILED
    except _Failure as exc:
        return _fail(str(exc), exc.status)
    except ImportError as exc:  # a capture file without the capture extra
        return missing_extra("gcu-async decode", "capture", exc)
    except ValueError as exc:  # not hex: a usage error
        return _fail(str(exc), EXIT_USAGE)
    except OSError as exc:  # a read error (a device that went away)
        return _fail(str(exc), EXIT_FAILED)
    return EXIT_OK


def _fail(message: str, status: int) -> int:
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        silence_stdout()
    print(f"gcu-async decode: {message}", file=sys.stderr)
    return status
