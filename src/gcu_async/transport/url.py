"""Make a transport from a URL: ``udp://HOST[:PORT]``, ``tcp://HOST[:PORT]``,
``serial:///dev/ttyUSB0?baudrate=115200`` (or ``serial:/dev/ttyUSB0``; on Windows
``serial://COM3``, see :func:`serial_device`).

IPv6 literals go in brackets (``udp://[::1]:2337``). Default ports follow docs/protocol-notes.md §12
"Transports": UDP 2337 (the host listens on 2338), TCP 2332.

Options come from the query string and/or keyword arguments of :func:`open_transport`.
Query values are text (booleans as 1/0, true/false, yes/no, on/off; ``none`` for an unset
bound); keyword values must be the native type (``local_port=0``, ``broadcast=True``: text
such as ``"false"`` is refused there, it is no bool). **Giving the same option both
ways is an error** (ValueError), as is an unknown option, a repeated query key, a user
name, a path, or a fragment. Options per scheme:

- every scheme, how a lost link is restored: ``reconnect``, ``backoff_base`` (s),
  ``backoff_factor``, ``backoff_cap`` (s), ``max_attempts`` (or none, the default),
  ``max_total`` (s, or none, the default); keyword only: ``rng`` (a :class:`random.Random`)
- udp: ``local_port`` (default 2338, 0 = ephemeral), ``local_host``, ``broadcast``,
  ``discovery``, ``follow_peer``, ``reuse_port`` (see
  :class:`~gcu_async.transport.udp.UdpTransport`)
- tcp: ``connect_timeout`` (s)
- serial: ``baudrate`` (115200, 250000, 500000 or 1000000)

Every error is a one-line ValueError that starts with the URL and names the field.

:func:`split_url` holds the rules for the scheme, host, port and device: the simulator's
listen URLs (:func:`gcu_async.sim.parse_listen_url`) are taken apart by the same function,
so a URL means the same place to both (a listen URL may also say ``pty``, and port 0 for
"any free port").
"""

from __future__ import annotations

import ipaddress
import re
from collections.abc import Mapping
from urllib.parse import parse_qsl, unquote, urlsplit

from gcu_async.transport.base import Transport
from gcu_async.transport.options import Converter, check_host
from gcu_async.transport.registry import KINDS, UrlParts, allowed_schemes, kind_of

__all__ = [
    "Converter", "UrlParts", "check_host", "merge_options", "open_transport", "serial_device",
    "split_hostport", "split_url",
]  # fmt: skip

_SCHEMES: dict[str, Mapping[str, Converter]] = {
    k.scheme: k.options for k in KINDS.values() if k.connect is not None
}
"""The client's options per scheme (read from the registry)."""


def open_transport(url: str, **options: object) -> Transport:
    """Build the transport ``url`` names (not yet opened: use ``async with`` or ``open()``).

    Raises ValueError, starting with the URL and naming the field, for an unknown scheme or
    option, a bad host, port or option value, or an option given both in the query and as
    a keyword argument.
    """
    if not isinstance(url, str):
        raise ValueError(f"url: {url!r} is not a string")
    try:
        return _build(url, options)
    except ValueError as exc:
        raise ValueError(f"{url or repr(url)}: {exc}") from exc


def split_url(url: str, *, listen: bool = False) -> UrlParts:
    """Take a GCU URL apart: the rules shared by the client's transports and the
    simulator's listen URLs.

    Schemes ``udp``, ``tcp`` and ``serial`` (any case); with ``listen``, also ``pty``. A
    udp/tcp URL is ``scheme://HOST[:PORT]`` (IPv6 in brackets; no user name or path), the
    port 1-65535 (with ``listen`` 0-65535: 0 binds any free port), by default the GCU's
    (UDP 2337, TCP 2332: docs/protocol-notes.md §12 "Transports"). A serial URL names its
    device as :func:`serial_device` says. No fragment. Raises ValueError naming the field
    (``scheme``, ``host``, ``port``, ``path``, ``device``, ``fragment``); the caller adds
    the URL in front.
    """
    if listen:
        bare = url.strip().lower()
        for kind in KINDS.values():
            if kind.address == "none" and bare in (kind.scheme, f"{kind.scheme}:",
                                                    f"{kind.scheme}://"):  # fmt: skip
                return UrlParts(kind.scheme)
    try:
        parts = urlsplit(url)
    except ValueError as exc:
        raise ValueError(f"host: cannot parse ({exc})") from None
    if not parts.scheme:
        raise ValueError(f"scheme: missing (use {allowed_schemes(listen=listen)})")
    kind = kind_of(parts.scheme, listen=listen)
    scheme = kind.scheme
    if kind.address == "none":
        raise ValueError(f"scheme: {kind.form} takes nothing after it (use {kind.form})")
    if parts.fragment:
        raise ValueError(f"fragment: {parts.fragment!r} is not allowed")
    if kind.address == "device":
        return UrlParts(scheme, device=serial_device(parts.netloc, parts.path), query=parts.query)
    if parts.path not in ("", "/"):
        raise ValueError(f"path: {parts.path!r} is not allowed (use {scheme}://HOST[:PORT])")
    lowest = 0 if listen else 1
    host, port = split_hostport(parts.netloc, kind.default_port, lowest_port=lowest)
    return UrlParts(scheme, host, port, query=parts.query)


def _build(url: str, kwargs: Mapping[str, object]) -> Transport:
    parts = split_url(url)
    kind = KINDS[parts.scheme]
    assert kind.connect is not None  # split_url took a client's scheme
    return kind.connect(parts, merge_options(parts.scheme, parts.query, kwargs))


def merge_options(
    scheme: str,
    query: str,
    kwargs: Mapping[str, object],
    allowed: Mapping[str, Converter] | None = None,
) -> dict[str, object]:
    """The options of a URL's query and of keyword arguments, converted; ``allowed``: the
    options a URL of ``scheme`` takes (default: a transport's)."""
    kind = KINDS[scheme]
    allowed = kind.options if allowed is None else allowed
    keyword_only = kind.keyword_only
    names = ", ".join(sorted(allowed))
    query_names = ", ".join(sorted(set(allowed) - keyword_only))
    raw: dict[str, tuple[object, bool]] = {}
    try:
        pairs = parse_qsl(query, keep_blank_values=True, strict_parsing=bool(query))
    except ValueError:
        raise ValueError(f"query: {query!r} is not name=value pairs joined by &") from None
    for name, value in pairs:
        if name not in allowed or name in keyword_only:
            raise ValueError(
                f"option: {name!r} is not a {scheme} URL option (allowed: {query_names})"
            )
        if name in raw:
            raise ValueError(f"option: {name!r} is given twice in the query")
        raw[name] = (value, True)
    for name, option in kwargs.items():
        if name not in allowed:
            raise ValueError(f"option: {name!r} is not a {scheme} option (allowed: {names})")
        if name in raw:
            raise ValueError(
                f"option: {name!r} is given both in the URL query and as a keyword argument"
            )
        raw[name] = (option, False)
    return {name: allowed[name](name, value, text) for name, (value, text) in raw.items()}


def split_hostport(
    netloc: str, default_port: int | None, *, lowest_port: int = 1
) -> tuple[str, int]:
    """``HOST[:PORT]`` (an IPv6 address in brackets) → (host, port); the port must be in
    ``lowest_port``-65535, and is required when ``default_port`` is ``None``. Raises
    ValueError naming the field (``host`` or ``port``)."""
    if "@" in netloc:
        raise ValueError("host: user information ('...@') is not allowed")
    port_text: str | None = None
    if netloc.startswith("["):
        end = netloc.find("]")
        host = unquote(netloc[1:end])  # RFC 6874 zone id: [fe80::1%25eth0]
        rest = netloc[end + 1 :]
        if rest:
            if not rest.startswith(":"):
                raise ValueError(f"host: unexpected {rest!r} after {netloc[: end + 1]!r}")
            port_text = rest[1:]
        try:
            ipaddress.IPv6Address(host)
        except ValueError:
            raise ValueError(f"host: {host!r} is not a valid IPv6 address") from None
    else:
        host, colon, port_part = netloc.partition(":")
        if ":" in port_part:
            raise ValueError(f"host: {netloc!r}: put an IPv6 address in brackets ([::1]:2337)")
        if colon:
            port_text = port_part
        if not host:
            raise ValueError("host: missing (use scheme://HOST[:PORT])")
        check_host("host", host)
    if port_text is None:
        if default_port is None:
            raise ValueError(f"port: missing (use HOST:PORT, port {lowest_port}-65535)")
        return host, default_port
    if not port_text.isdigit() or not lowest_port <= int(port_text) <= 65535:
        raise ValueError(f"port: {port_text!r} is not a valid port (allowed {lowest_port}-65535)")
    return host, int(port_text)


_WINDOWS_PORT = re.compile(r"COM[1-9][0-9]*\Z", re.IGNORECASE)


def serial_device(netloc: str, path: str) -> str:
    """The device a ``serial:`` URL names, from its host part and path (still quoted).

    A POSIX path: ``serial:///dev/ttyUSB0`` or ``serial:/dev/ttyUSB0``. A Windows port
    name (``COM`` and a number, any case): ``serial://COM3``, ``serial:COM3`` and also
    ``serial:///COM3`` (no POSIX serial device sits at ``/COMn``) all name ``COM3``. Raises
    ValueError (field ``device``) for any other host part or a missing device.
    """
    if netloc:
        name = unquote(netloc)
        if path not in ("", "/") or not _WINDOWS_PORT.match(name):
            raise ValueError(
                f"device: host part {netloc!r} is not allowed "
                "(use serial:///dev/ttyUSB0, or serial://COM3 on Windows)"
            )
        return name
    device = unquote(path)
    if device.startswith("/") and _WINDOWS_PORT.match(device[1:]):
        return device[1:]
    if not device or device == "/":
        raise ValueError("device: missing (use serial:///dev/ttyUSB0, or serial://COM3 on Windows)")
    return device
