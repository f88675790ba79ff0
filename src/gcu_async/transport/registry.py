"""The transport registry: one :class:`TransportKind` record per URL scheme.

Everything that depends on the scheme reads it here: the client's URLs
(:func:`~gcu_async.transport.url.open_transport`), the simulator's listen URLs
(:func:`~gcu_async.sim.parse_listen_url`, :meth:`~gcu_async.sim.GcuSimulator.serve`) and the
pytest plugin's endpoints. Adding a transport is one record here plus its modules (a
:class:`~gcu_async.transport.Transport` subclass and a simulator server):
docs/architecture.md, "Adding a transport".

The simulator's side is named by ``"module:function"`` and imported when first used: the
simulator imports this package, never the other way round.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Literal

from gcu_async.protocol.links import DEFAULT_BAUDRATE, GCU_TCP_PORT, GCU_UDP_PORT
from gcu_async.transport.backoff import Backoff
from gcu_async.transport.base import Transport
from gcu_async.transport.options import (
    Converter,
    as_baudrate,
    as_bool,
    as_float,
    as_host,
    as_int,
    as_rng,
    optional,
)
from gcu_async.transport.serial import SerialTransport
from gcu_async.transport.tcp import TcpTransport
from gcu_async.transport.udp import UdpTransport


@dataclass(frozen=True)
class UrlParts:
    """A URL taken apart by :func:`~gcu_async.transport.url.split_url`."""

    scheme: str
    """``udp``, ``tcp``, ``serial`` (or, for a listen URL, ``pty``), in lower case."""
    host: str = ""
    """udp/tcp: the host name or address (an IPv6 address without its brackets)."""
    port: int = 0
    """udp/tcp: the port, or the GCU's default for the scheme when the URL gives none."""
    device: str = ""
    """serial: the device (``/dev/ttyUSB0``, ``COM3``; see
    :func:`~gcu_async.transport.url.serial_device`)."""
    query: str = ""
    """The query string, still to be read as options."""


Connect = Callable[[UrlParts, dict[str, object]], Transport]
"""(the URL's parts, its converted options) → the client's transport, not yet opened."""


@dataclass(frozen=True)
class TransportKind:
    """What the library knows of one URL scheme."""

    scheme: str
    """The URL scheme (lower case)."""
    address: Literal["host", "device", "none"]
    """What the URL names: ``host`` (``scheme://HOST[:PORT]``), ``device``
    (``serial:///dev/ttyUSB0``) or ``none`` (the bare word: ``pty``)."""
    transport: type[Transport]
    """The client's transport class (for ``pty``: the one that opens the pty's device). Its
    ``ordered`` and ``datagram`` say whether the link may reorder and keeps datagrams."""
    connect: Connect | None
    """The client's factory; ``None``: a listen-only scheme (``pty``)."""
    listener: str | None
    """The simulator's factory ``(ServerParts, ListenSpec) → SimServer``, as
    ``"module:function"``; ``None``: the simulator cannot listen there."""
    default_port: int | None = None
    """``host`` URLs: the GCU's port when the URL gives none (docs/protocol-notes.md §12)."""
    options: Mapping[str, Converter] = field(default_factory=dict)
    """The client's options (URL query or keyword argument) and their converters."""
    keyword_only: frozenset[str] = frozenset()
    """Options a URL query cannot give (they are no text: ``rng``)."""
    listen_options: Mapping[str, Converter] = field(default_factory=dict)
    """The listen URL's query options; each is a field of :class:`~gcu_async.sim.ListenSpec`."""
    fixture_listen: str | None = None
    """The loopback listen URL the pytest plugin's ``gcu_sim`` uses for this transport
    (``None``: the plugin does not offer it)."""
    fixture_client: Mapping[str, object] = field(default_factory=dict)
    """Options the plugin's client gets for this transport (``local_port=0`` for UDP)."""

    @property
    def ordered(self) -> bool:
        """Packets arrive in the order sent (no reorder guard needed)."""
        return self.transport.ordered

    @property
    def datagram(self) -> bool:
        """Every ``on_data`` call carries exactly one datagram."""
        return self.transport.datagram

    @property
    def form(self) -> str:
        """How the scheme is written in messages (``udp://``, ``pty``)."""
        return self.scheme if self.address == "none" else f"{self.scheme}://"


_BACKOFF_FIELDS = (
    ("backoff_base", "base"), ("backoff_factor", "factor"), ("backoff_cap", "cap"),
    ("max_attempts", "max_attempts"), ("max_total", "max_total"),
)  # fmt: skip
_RECONNECT_OPTIONS: dict[str, Converter] = {
    "reconnect": as_bool, "backoff_base": as_float, "backoff_factor": as_float,
    "backoff_cap": as_float, "max_attempts": optional(as_int), "max_total": optional(as_float),
    "rng": as_rng,
}  # fmt: skip
"""How every transport that restores a lost link takes its schedule (docs/transports.md,
"Reconnecting"): the :class:`Backoff` fields by name, ``reconnect`` and ``rng``."""


def _with_backoff(options: dict[str, object]) -> dict[str, object]:
    """``options`` with the :class:`Backoff` fields folded into ``backoff`` (when any is
    given; otherwise the transport's default schedule)."""
    fields = {field: options.pop(name) for name, field in _BACKOFF_FIELDS if name in options}
    if fields:
        options["backoff"] = Backoff(**fields)  # type: ignore[arg-type]
    return options


def _udp(parts: UrlParts, options: dict[str, object]) -> Transport:
    return UdpTransport(parts.host, parts.port, **_with_backoff(options))  # type: ignore[arg-type]


def _tcp(parts: UrlParts, options: dict[str, object]) -> Transport:
    return TcpTransport(parts.host, parts.port, **_with_backoff(options))  # type: ignore[arg-type]


def _serial(parts: UrlParts, options: dict[str, object]) -> Transport:
    options = _with_backoff(options)
    baudrate = options.pop("baudrate", DEFAULT_BAUDRATE)
    return SerialTransport(parts.device, baudrate, **options)  # type: ignore[arg-type]


_SERIAL_OPTIONS: dict[str, Converter] = {"baudrate": as_baudrate}

KINDS: dict[str, TransportKind] = {
    kind.scheme: kind
    for kind in (
        TransportKind(
            "udp", "host", UdpTransport, _udp, "gcu_async.sim.udp:listen",
            default_port=GCU_UDP_PORT,
            options={
                "local_port": as_int, "local_host": as_host, "broadcast": as_bool,
                "discovery": as_bool, "follow_peer": as_bool, "reuse_port": optional(as_bool),
                **_RECONNECT_OPTIONS,
            },
            keyword_only=frozenset({"rng"}),
            fixture_listen="udp://127.0.0.1:0", fixture_client={"local_port": 0},
        ),
        TransportKind(
            "tcp", "host", TcpTransport, _tcp, "gcu_async.sim.tcp:listen",
            default_port=GCU_TCP_PORT,
            options={"connect_timeout": as_float, **_RECONNECT_OPTIONS},
            keyword_only=frozenset({"rng"}),
            fixture_listen="tcp://127.0.0.1:0",
        ),
        TransportKind(
            "serial", "device", SerialTransport, _serial, "gcu_async.sim.serialport:listen",
            options={**_SERIAL_OPTIONS, **_RECONNECT_OPTIONS},
            keyword_only=frozenset({"rng"}),
            listen_options=_SERIAL_OPTIONS, fixture_listen="pty",
        ),
        TransportKind("pty", "none", SerialTransport, None, "gcu_async.sim.serialport:listen_pty"),
    )
}  # fmt: skip
"""Every scheme, in the order messages list them."""


def allowed_schemes(*, listen: bool) -> str:
    """The schemes a client (or, with ``listen``, a simulator) takes, as messages list them:
    ``udp://, tcp:// or serial://``."""
    forms = [k.form for k in KINDS.values() if (k.listener if listen else k.connect)]
    return f"{', '.join(forms[:-1])} or {forms[-1]}"


def kind_of(scheme: str, *, listen: bool = False) -> TransportKind:
    """The record of ``scheme`` (any case) a client (or, with ``listen``, a simulator) can
    use; ValueError naming the field ``scheme`` otherwise."""
    kind = KINDS.get(scheme.lower())
    if kind is None or (kind.listener if listen else kind.connect) is None:
        allowed = allowed_schemes(listen=listen)
        raise ValueError(f"scheme: {scheme!r} is not supported (allowed: {allowed})")
    return kind
