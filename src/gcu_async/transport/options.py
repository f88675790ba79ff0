"""Converters of transport options: a URL query's text or a keyword argument's value →
the option's value, or a one-line ValueError naming the field.

A :class:`~gcu_async.transport.registry.TransportKind` lists its options as ``{name:
converter}``; query values are text (booleans as 1/0, true/false, yes/no, on/off; ``none``
for an unset bound), keyword values must be the native type.
"""

from __future__ import annotations

import ipaddress
import random
import re
from collections.abc import Callable
from typing import TypedDict

from gcu_async.transport.serial import check_baudrate

Converter = Callable[[str, object, bool], object]
"""(field, value, value is query text) → the option's value, or ValueError."""

_LABEL = re.compile(r"(?!-)[A-Za-z0-9-]{1,63}(?<!-)\Z")
_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


class TransportOptions(TypedDict, total=False):
    """Every transport's keyword options, for type checkers (``connect(url, **options)``);
    which a scheme takes is its registry record's ``options``
    (:data:`~gcu_async.transport.registry.KINDS`), which checks them at run time. TCP's
    ``connect_timeout`` is not here: to :func:`~gcu_async.connect` that keyword is the
    client's (the URL query gives the transport's)."""

    local_port: int
    local_host: str
    broadcast: bool
    discovery: bool
    follow_peer: bool
    reuse_port: bool | None
    baudrate: int
    reconnect: bool
    backoff_base: float
    backoff_factor: float
    backoff_cap: float
    max_attempts: int | None
    max_total: float | None
    rng: random.Random


def check_host(field: str, host: str) -> str:
    """Return ``host`` if it is an IP address or a valid DNS name, else raise ValueError."""
    try:
        ipaddress.ip_address(host)
        return host
    except ValueError:
        pass
    if ":" in host:
        raise ValueError(f"{field}: {host!r} is not a valid IPv6 address")
    if re.fullmatch(r"[0-9.]+", host):
        raise ValueError(f"{field}: {host!r} is not a valid IPv4 address")
    name = host[:-1] if host.endswith(".") else host
    if not name or len(name) > 253 or not all(_LABEL.match(p) for p in name.split(".")):
        raise ValueError(f"{field}: {host!r} is not a valid host name or address")
    return host


def as_int(field: str, value: object, text: bool) -> object:
    if text and isinstance(value, str):
        if not re.fullmatch(r"[+-]?[0-9]+", value.strip()):
            raise ValueError(f"{field}: {value!r} is not an integer")
        return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{field}: {value!r} is not an integer (an int)")
    return value


def as_float(field: str, value: object, text: bool) -> object:
    if text and isinstance(value, str):
        try:
            return float(value)
        except ValueError:
            raise ValueError(f"{field}: {value!r} is not a number") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{field}: {value!r} is not a number (an int or float)")
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{field}: {value!r} is too large for a number of seconds") from None


def as_bool(field: str, value: object, text: bool) -> object:
    if isinstance(value, bool):
        return value
    if text and isinstance(value, str) and value.strip().lower() in _TRUE | _FALSE:
        return value.strip().lower() in _TRUE
    if text:
        raise ValueError(
            f"{field}: {value!r} is not a boolean (use 1/0, true/false, yes/no, on/off)"
        )
    raise ValueError(f"{field}: {value!r} is not a bool (True or False)")


def optional(conv: Converter) -> Converter:
    def convert(field: str, value: object, text: bool) -> object:
        if value is None or (text and isinstance(value, str) and value.strip().lower() == "none"):
            return None
        return conv(field, value, text)

    return convert


def as_host(field: str, value: object, text: bool) -> object:
    if not isinstance(value, str):
        raise ValueError(f"{field}: {value!r} is not a host name or address")
    return check_host(field, value)


def as_rng(field: str, value: object, text: bool) -> object:
    if not isinstance(value, random.Random):
        raise ValueError(f"{field}: {value!r} is not a random.Random")
    return value


def as_baudrate(field: str, value: object, text: bool) -> object:
    return check_baudrate(as_int(field, value, text))
