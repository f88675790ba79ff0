"""Small helpers shared by the socket and serial transports (not public API)."""

from __future__ import annotations

import asyncio
import ipaddress
from collections.abc import Callable
from typing import TypeVar

from gcu_async._checks import type_error
from gcu_async.errors import LinkLost

T = TypeVar("T")


def link_lost(where: str, doing: str, exc: BaseException) -> LinkLost:
    """The one conversion of a transport's OS error (or timeout) into :class:`LinkLost`:
    ``"<where>: <doing>: <error>"`` (without the error when it has no text, as a timeout).
    Raise it ``from exc`` so the cause stays attached."""
    text = str(exc)
    return LinkLost(f"{where}: {doing}: {text}" if text else f"{where}: {doing}")


def check_port(field: str, value: object, *, allow_zero: bool = False) -> int:
    """Return ``value`` as a port number or raise ValueError naming ``field``."""
    low = 0 if allow_zero else 1
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= 65535:
        raise ValueError(f"{field}: {value!r} is not a valid port (allowed {low}-65535)")
    return value


def check_positive(field: str, value: object, *, allow_zero: bool = False) -> float:
    """Return ``value`` as a float > 0 (or >= 0) or raise ValueError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{field}: {value!r} is not a number")
    ok = value >= 0 if allow_zero else value > 0
    if not ok or value != value or value == float("inf"):
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{field}: {value!r} is out of range (allowed: finite, {bound})")
    return float(value)


def check_reason(value: object) -> str:
    """Return ``value`` if it is a ``str`` (the reason given to ``Transport.reset``), else
    raise TypeError naming the field."""
    if not isinstance(value, str):
        raise type_error("reason", "a str", value)
    return value


def format_hostport(host: str, port: int) -> str:
    """``host:port`` with IPv6 literals in brackets (``[::1]:2337``)."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def same_address(a: tuple[str, int], b: tuple[str, int]) -> bool:
    """True when two (host, port) socket addresses name the same endpoint."""
    if a == b:  # the common case, per received datagram: skip parsing the addresses
        return True
    if a[1] != b[1]:
        return False
    try:
        return ipaddress.ip_address(a[0]) == ipaddress.ip_address(b[0])
    except ValueError:
        return a[0] == b[0]


def call_guarded(handler: Callable[[T], None], arg: T, what: str) -> None:
    """Call a user handler; an exception goes to the loop's exception handler instead of
    tearing down the link (asyncio would otherwise close a stream on a protocol error)."""
    try:
        handler(arg)
    except Exception as exc:
        asyncio.get_running_loop().call_exception_handler(
            {"message": f"gcu_async transport: {what} handler raised", "exception": exc}
        )
