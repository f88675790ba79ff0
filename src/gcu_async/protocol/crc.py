"""CRC-16/XMODEM over bytes 0..S-3, sent high byte first (the one big-endian field).

The document's nibble-table C function computes exactly CRC-16/XMODEM (poly 0x1021,
init 0, no reflection, no final xor), which the standard library implements in C.
"""

from __future__ import annotations

from binascii import crc_hqx

from gcu_async._checks import type_error


def crc16_xmodem(data: bytes | bytearray | memoryview) -> int:
    """CRC-16/XMODEM of ``data`` (``bytes``, ``bytearray`` or ``memoryview``; anything else
    is a ``TypeError`` naming ``data``)."""
    if not isinstance(data, (bytes, bytearray, memoryview)):
        raise type_error("data", "bytes, bytearray or memoryview", data)
    return crc_hqx(data, 0)
