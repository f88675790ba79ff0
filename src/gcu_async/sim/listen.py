"""Listen URLs of the simulator: ``udp://HOST[:PORT]``, ``tcp://HOST[:PORT]``, ``pty``,
``serial:///dev/ttyX[?baudrate=N]``."""

from __future__ import annotations

from dataclasses import dataclass
from urllib.parse import parse_qs, urlsplit

from gcu_async.sim.serialport import DEFAULT_BAUDRATE
from gcu_async.sim.tcp import GCU_TCP_PORT
from gcu_async.sim.udp import GCU_UDP_PORT
from gcu_async.transport.url import serial_device

SERIAL_BAUDRATES = (115200, 250000, 500000, 1000000)
_DEFAULT_PORTS = {"udp": GCU_UDP_PORT, "tcp": GCU_TCP_PORT}
EXAMPLES = "udp://127.0.0.1:2337, tcp://127.0.0.1:2332, pty, serial:///dev/ttyUSB0?baudrate=115200"


@dataclass(frozen=True)
class ListenSpec:
    """Where a simulator endpoint listens."""

    kind: str
    """``udp``, ``tcp``, ``pty`` or ``serial``."""
    host: str = ""
    port: int = 0
    path: str = ""
    baudrate: int = DEFAULT_BAUDRATE
    reply_to: tuple[str, int] | None = None
    """UDP: send every reply to this address instead of the sender."""
    reply_port: int | None = None
    """UDP: send replies to the sender's host at this port."""


def parse_hostport(text: str, *, what: str = "address") -> tuple[str, int]:
    """``HOST:PORT`` (IPv6 in brackets) → (host, port); ``ValueError`` naming the problem."""
    parts = urlsplit(f"//{text}")
    try:
        port = parts.port
    except ValueError:
        raise ValueError(f"{what} {text!r}: port must be a number in 0-65535") from None
    if not parts.hostname or port is None:
        raise ValueError(f"{what} {text!r}: expected HOST:PORT")
    return parts.hostname, port


def parse_listen_url(url: str) -> ListenSpec:
    """Parse a listen URL; raises ``ValueError`` with a one-line message on any problem."""
    text = url.strip()
    if text in ("pty", "pty:", "pty://"):
        return ListenSpec("pty")
    parts = urlsplit(text)
    scheme = parts.scheme.lower()
    if scheme in _DEFAULT_PORTS:
        try:
            port = parts.port
        except ValueError:
            raise ValueError(f"listen URL {url!r}: port must be a number in 0-65535") from None
        if not parts.hostname:
            raise ValueError(f"listen URL {url!r}: missing host (e.g. {scheme}://127.0.0.1)")
        if parts.path not in ("", "/") or parts.query:
            raise ValueError(f"listen URL {url!r}: unexpected path or query after the port")
        return ListenSpec(scheme, parts.hostname,
                          _DEFAULT_PORTS[scheme] if port is None else port)  # fmt: skip
    if scheme == "serial":
        try:
            path = serial_device(parts.netloc, parts.path)  # the client's rule (COM3 too)
        except ValueError as exc:
            raise ValueError(f"listen URL {url!r}: {exc}") from None
        query = parse_qs(parts.query)
        unknown = set(query) - {"baudrate"}
        if unknown:
            raise ValueError(f"listen URL {url!r}: unknown option {sorted(unknown)[0]!r}")
        baudrate = DEFAULT_BAUDRATE
        if "baudrate" in query:
            raw = query["baudrate"][-1]
            if not raw.isdigit() or int(raw) <= 0:
                raise ValueError(f"listen URL {url!r}: baudrate {raw!r} is not a positive number")
            baudrate = int(raw)
        return ListenSpec("serial", path=path, baudrate=baudrate)
    raise ValueError(f"listen URL {url!r}: expected one of {EXAMPLES}")
