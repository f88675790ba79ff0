"""The capture libraries, imported only when a capture is written or read.

gcu_async's runtime dependencies are the standard library and pyserial-asyncio; captures
use two small, pure-Python libraries from the ``capture`` extra: **python-pcapng** (writing
pcapng files: sections, several interfaces with their link types, per-packet options such as
the direction flags) and **dpkt** (IPv4/IPv6, UDP and TCP headers with their checksums;
Ethernet and Linux cooked-capture framing of captures made by tcpdump/dumpcap). Reading a
file's record and block structure is :mod:`~gcu_async.capture.blocks`' own (it says why).
"""

from __future__ import annotations

import functools
from types import ModuleType
from typing import Any

INSTALL_HINT = "pip install 'gcu-async[capture]'"


class CaptureUnavailable(ImportError):
    """The ``capture`` extra (dpkt, python-pcapng) is not installed."""


def _missing(exc: ImportError) -> CaptureUnavailable:
    return CaptureUnavailable(
        f"packet captures need the 'capture' extra (dpkt and python-pcapng), which is not "
        f"installed ({exc}): {INSTALL_HINT}"
    )


@functools.cache  # called per packet when reading: import statements are not free
def dpkt() -> Any:
    """The ``dpkt`` package with its IP, UDP, TCP, Ethernet, SLL and pcap modules loaded."""
    try:
        import dpkt as module
        import dpkt.ethernet
        import dpkt.ip
        import dpkt.ip6
        import dpkt.pcap
        import dpkt.sll
        import dpkt.sll2
        import dpkt.tcp
        import dpkt.udp
    except ImportError as exc:
        raise _missing(exc) from exc
    return module


def pcapng() -> Any:
    """The ``pcapng`` package (python-pcapng) with its ``blocks`` module loaded."""
    try:
        import pcapng as module
        import pcapng.blocks  # loads pcapng.blocks
    except ImportError as exc:
        raise _missing(exc) from exc
    return module


def require() -> tuple[ModuleType, ModuleType]:
    """Both libraries, or :class:`CaptureUnavailable` naming the extra."""
    return dpkt(), pcapng()
