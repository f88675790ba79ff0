"""Listen URLs of the simulator: ``udp://HOST[:PORT]``, ``tcp://HOST[:PORT]``, ``pty``,
``serial:///dev/ttyX[?baudrate=N]``.

They are taken apart by the client's own :func:`~gcu_async.transport.url.split_url`: a URL
names the same place for a client and a simulator (the same schemes, hosts, default ports,
serial devices and baud rates); a listen URL may also be ``pty``, and port 0 (any free port).
"""

from __future__ import annotations

from dataclasses import dataclass

from gcu_async.protocol.links import DEFAULT_BAUDRATE
from gcu_async.transport.registry import KINDS
from gcu_async.transport.url import merge_options, split_hostport, split_url

EXAMPLES = "udp://127.0.0.1:2337, tcp://127.0.0.1:2332, pty, serial:///dev/ttyUSB0?baudrate=115200"


@dataclass(frozen=True)
class ListenSpec:
    """Where a simulator endpoint listens."""

    kind: str
    """The scheme (a :data:`~gcu_async.transport.registry.KINDS` key): ``udp``, ``tcp``,
    ``pty`` or ``serial``."""
    host: str = ""
    port: int = 0
    path: str = ""
    baudrate: int = DEFAULT_BAUDRATE
    reply_to: tuple[str, int] | None = None
    """UDP: send every reply to this address instead of the sender."""
    reply_port: int | None = None
    """UDP: send replies to the sender's host at this port."""


def parse_hostport(text: str, *, what: str = "address") -> tuple[str, int]:
    """``HOST:PORT`` (IPv6 in brackets, port 1-65535) → (host, port), by the URLs' rules;
    ``ValueError`` naming ``what`` and the problem."""
    try:
        return split_hostport(text, None)
    except ValueError as exc:
        raise ValueError(f"{what} {text!r}: {exc}") from None


def parse_listen_url(url: str) -> ListenSpec:
    """Parse a listen URL; raises ``ValueError`` with a one-line message on any problem
    (``listen URL 'URL': FIELD: ...``)."""
    try:
        parts = split_url(url, listen=True)
        allowed = KINDS[parts.scheme].listen_options
        options = merge_options(parts.scheme, parts.query, {}, allowed)
    except ValueError as exc:
        raise ValueError(f"listen URL {url!r}: {exc}") from None
    # each listen option is a ListenSpec field (registry.TransportKind.listen_options)
    return ListenSpec(parts.scheme, parts.host, parts.port, parts.device,
                      **options)  # type: ignore[arg-type]  # fmt: skip
