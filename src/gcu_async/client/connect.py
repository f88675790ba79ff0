"""``connect(url, **options)``: a :class:`GcuClient` over the transport a URL names.

Its options are :class:`GcuClient`'s keyword arguments (the client's and its session's),
taken from ``GcuClient`` itself (the signature :func:`inspect.signature` shows is built from
it), and the options of the URL's transport. For type checkers they are
:class:`ConnectOptions`, so that a misspelt or mistyped option is an error before anything
runs; at run time an unknown one is a ``ValueError`` that lists both kinds and suggests the
closest name.
"""

from __future__ import annotations

import inspect
import os
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypedDict

from gcu_async._checks import did_you_mean, type_error
from gcu_async.capture.writer import PacketCapture
from gcu_async.client.client import GcuClient
from gcu_async.transport.options import TransportOptions
from gcu_async.transport.registry import KINDS
from gcu_async.transport.url import open_transport, split_url

if sys.version_info >= (3, 11):
    from typing import Unpack
elif TYPE_CHECKING:
    from typing_extensions import Unpack

_CLIENT_KEYWORDS = [
    p for p in inspect.signature(GcuClient).parameters.values()
    if p.kind is inspect.Parameter.KEYWORD_ONLY
]  # fmt: skip
CLIENT_OPTIONS = frozenset(p.name for p in _CLIENT_KEYWORDS)
"""Options of :func:`connect` that go to :class:`GcuClient` (its keyword arguments)."""


class ClientOptions(TypedDict, total=False):
    """:class:`GcuClient`'s keyword arguments, for type checkers (the signature is the
    reference: a test compares them)."""

    rate_hz: float
    command_timeout: float
    queue_timeout: float
    connect_timeout: float
    open_timeout: float | None
    wait: bool
    restore: bool
    silence_timeout: float
    check_support: bool
    reorder_guard: float | None
    aircraft_timeout: float
    version: int
    clock: Callable[[], float]
    capture: PacketCapture | str | os.PathLike[str] | None
    max_zoom: float | None
    conformance: bool


class ConnectOptions(ClientOptions, TransportOptions, total=False):
    """What :func:`connect` takes besides the URL: the client's options and the
    transport's (:class:`~gcu_async.transport.options.TransportOptions`)."""


def connect(url: str, **options: Unpack[ConnectOptions]) -> GcuClient:
    """A client for ``url`` — use it as ``async with connect(url) as gcu:``.

    URLs: ``udp://HOST[:PORT]`` (GCU port, default 2337), ``tcp://HOST[:PORT]`` (default
    2332), ``serial:///dev/ttyUSB0?baudrate=115200``. The options named like
    :class:`GcuClient`'s keyword arguments (``rate_hz``, ``command_timeout``, … : its
    signature is this function's) configure the client; the rest go to the transport (e.g.
    ``local_port``, ``discovery``, ``baudrate``, ``max_attempts``). ``connect_timeout`` as a
    keyword is the client's (the wait for the first reply); a TCP transport's own connect
    timeout goes in the URL (``tcp://HOST?connect_timeout=5``). ``wait=False`` opens in the
    background: ``async with connect(url, wait=False) as gcu:`` returns at once, and the
    link comes up when the GCU answers (docs/client.md, "Starting before the GCU"). A bad
    URL or option raises ``TypeError``/``ValueError`` before anything is opened (a ``url``
    that is not a ``str`` is a ``TypeError``; an option neither the client nor the URL's
    transport takes is a ``ValueError`` naming both kinds and the closest name).
    """
    if not isinstance(url, str):
        raise type_error("url", "a URL string (udp://, tcp:// or serial://)", url)
    try:
        scheme = split_url(url).scheme
    except ValueError:
        open_transport(url)  # raises it, naming the URL
        raise
    transport_names = KINDS[scheme].options.keys() - CLIENT_OPTIONS
    for name in options:
        if name not in CLIENT_OPTIONS and name not in transport_names:
            raise ValueError(_unknown(name, scheme, sorted(CLIENT_OPTIONS),
                                      sorted(transport_names)))  # fmt: skip
    client_options: dict[str, Any] = {k: v for k, v in options.items() if k in CLIENT_OPTIONS}
    transport_options = {k: v for k, v in options.items() if k not in CLIENT_OPTIONS}
    transport = open_transport(url, **transport_options)
    return GcuClient(transport, **client_options)


def _unknown(name: str, scheme: str, client: list[str], transport: list[str]) -> str:
    """The error of an option ``connect`` does not take: the closest name, then every one."""
    hint = did_you_mean(name, client + transport)
    hint = f" {hint}" if hint else ""
    return (f"option: {name!r} is not an option of the client or of a {scheme} "
            f"transport;{hint} (client and session: {', '.join(client)}; {scheme} "
            f"transport: {', '.join(transport)})")


connect.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
    [
        inspect.Parameter("url", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation="str"),
        *_CLIENT_KEYWORDS,
        inspect.Parameter("transport_options", inspect.Parameter.VAR_KEYWORD, annotation="Any"),
    ],
    return_annotation="GcuClient",
)

__all__ = ["CLIENT_OPTIONS", "ClientOptions", "ConnectOptions", "connect"]
