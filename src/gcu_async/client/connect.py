"""``connect(url, **options)``: a :class:`GcuClient` over the transport a URL names.

Its options are :class:`GcuClient`'s keyword arguments, taken from ``GcuClient`` itself (the
signature :func:`inspect.signature` shows is built from it), so the two cannot drift apart;
every other option goes to the transport.
"""

from __future__ import annotations

import inspect
from typing import Any

from gcu_async._checks import type_error
from gcu_async.client.client import GcuClient

_CLIENT_KEYWORDS = [
    p for p in inspect.signature(GcuClient).parameters.values()
    if p.kind is inspect.Parameter.KEYWORD_ONLY
]  # fmt: skip
CLIENT_OPTIONS = frozenset(p.name for p in _CLIENT_KEYWORDS)
"""Options of :func:`connect` that go to :class:`GcuClient` (its keyword arguments)."""


def connect(url: str, **options: Any) -> GcuClient:
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
    that is not a ``str`` is a ``TypeError``).
    """
    from gcu_async.transport.url import open_transport

    if not isinstance(url, str):
        raise type_error("url", "a URL string (udp://, tcp:// or serial://)", url)

    client_options = {k: v for k, v in options.items() if k in CLIENT_OPTIONS}
    transport_options = {k: v for k, v in options.items() if k not in CLIENT_OPTIONS}
    transport = open_transport(url, **transport_options)
    return GcuClient(transport, **client_options)


connect.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
    [
        inspect.Parameter("url", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation="str"),
        *_CLIENT_KEYWORDS,
        inspect.Parameter("transport_options", inspect.Parameter.VAR_KEYWORD, annotation="Any"),
    ],
    return_annotation="GcuClient",
)
