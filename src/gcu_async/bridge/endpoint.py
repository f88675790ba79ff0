"""MAVLink connection strings (``--mavlink``): the accepted forms, checked before anything opens.

pymavlink's spelling, restricted to what the bridge's links implement
(docs/mavlink-bridge.md, "Links"):

- ``udpout:HOST:PORT`` — send to a listener at HOST:PORT (and hear its replies);
- ``udpin:HOST:PORT`` — listen on HOST:PORT (port 0: any free port);
- ``tcp:HOST:PORT`` — connect to a TCP server (reconnected in the background);
- ``tcpin:HOST:PORT`` — accept TCP clients on HOST:PORT (port 0: any free port);
- ``DEVICE[,BAUD]`` — a serial device: a path (``/dev/ttyACM0,115200``) or ``COMn``.

HOST is an IPv4 address, a DNS name, or an IPv6 address in brackets (``udpin:[::1]:14550``).
Every error is one line that starts with the connection string and names the part at fault.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from gcu_async.transport.url import check_host

SCHEMES = ("udpout", "udpin", "tcp", "tcpin")
"""The network schemes; anything else with a ``scheme:`` prefix is refused."""
LISTENERS = ("udpin", "tcpin")
"""Schemes that bind HOST:PORT (and so may take port 0, any free port)."""
DEFAULT_BAUD = 115200
"""A serial device's rate when the string gives none (pymavlink's default)."""
BAUD_RANGE = (50, 4_000_000)
"""Serial rates accepted, inclusive (what Linux's termios can be asked for)."""
_HINTS = {"udp": "use udpin: to listen or udpout: to send to a listener",
          "serial": "give the device path alone, e.g. /dev/ttyACM0,115200"}  # fmt: skip


@dataclass(frozen=True)
class Endpoint:
    """One parsed connection string. ``kind`` is a scheme of :data:`SCHEMES` or ``serial``;
    network kinds have ``host`` and ``port``, ``serial`` has ``device`` and ``baud``."""

    text: str
    kind: str
    host: str = ""
    port: int = 0
    device: str = ""
    baud: int = 0


def parse_endpoint(text: str) -> Endpoint:
    """Parse and check ``text`` (ValueError, one line, naming the part at fault)."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"connection {text!r}: empty; give e.g. udpout:127.0.0.1:14550")
    if text.startswith("/") or re.fullmatch(r"COM[0-9]+(,.*)?", text, re.IGNORECASE):
        return _serial(text)
    scheme, sep, rest = text.partition(":")
    if not sep:
        raise ValueError(f"connection {text!r}: no scheme; use one of "
                         f"{', '.join(s + ':HOST:PORT' for s in SCHEMES)} or a serial device "
                         "path DEVICE[,BAUD]")  # fmt: skip
    if scheme not in SCHEMES:
        hint = _HINTS.get(scheme.lower(), f"use one of {', '.join(SCHEMES)}")
        raise ValueError(f"connection {text!r}: unknown scheme {scheme!r}; {hint}")
    host, port = _host_port(text, rest)
    low = 0 if scheme in LISTENERS else 1
    if not low <= port <= 65535:
        raise ValueError(f"connection {text!r}: port {port} is outside the allowed range "
                         f"[{low}, 65535]")  # fmt: skip
    return Endpoint(text, scheme, host=host, port=port)


def _host_port(text: str, rest: str) -> tuple[str, int]:
    if rest.startswith("["):
        host, bracket, after = rest[1:].partition("]")
        if not bracket or not after.startswith(":"):
            raise ValueError(f"connection {text!r}: expected [IPV6]:PORT")
        port_text = after[1:]
    else:
        host, sep, port_text = rest.rpartition(":")
        if not sep:
            raise ValueError(f"connection {text!r}: no port; expected HOST:PORT")
        if ":" in host:
            raise ValueError(f"connection {text!r}: an IPv6 address goes in brackets, "
                             f"e.g. {text.partition(':')[0]}:[::1]:14550")  # fmt: skip
    if not host:
        raise ValueError(f"connection {text!r}: no host; expected HOST:PORT")
    try:
        check_host("host", host)
    except ValueError as exc:
        raise ValueError(f"connection {text!r}: {exc}") from None
    if not re.fullmatch(r"[0-9]{1,5}", port_text):
        raise ValueError(f"connection {text!r}: port {port_text!r} is not a number "
                         "in [0, 65535]")  # fmt: skip
    return host, int(port_text)


def _serial(text: str) -> Endpoint:
    device, sep, baud_text = text.partition(",")
    if not device or device.endswith("/"):
        raise ValueError(f"connection {text!r}: no serial device path")
    baud = DEFAULT_BAUD
    if sep:
        if not re.fullmatch(r"[0-9]{1,8}", baud_text):
            raise ValueError(f"connection {text!r}: baud {baud_text!r} is not a whole number")
        baud = int(baud_text)
        low, high = BAUD_RANGE
        if not low <= baud <= high:
            raise ValueError(f"connection {text!r}: baud {baud} is outside the allowed range "
                             f"[{low}, {high}]")  # fmt: skip
    return Endpoint(text, "serial", device=device, baud=baud)
