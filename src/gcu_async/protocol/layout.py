"""Facts of the packet layout that host and GCU packets share: where each part sits, the raw
range of the signed integer fields, and the header byte of the standard sub frame."""

from __future__ import annotations

from gcu_async.protocol.fields import WIRE_RANGES

S16 = WIRE_RANGES["h"]
"""Raw range of a signed 16-bit field (little-endian on the wire)."""
S32 = WIRE_RANGES["i"]
"""Raw range of a signed 32-bit field (little-endian on the wire)."""
SUB_FRAME_HEADER = 0x01
"""Byte 37 of a standard sub frame, in either direction (the only one V2.0.6 defines)."""

PREFIX_SIZE = 5
"""Bytes 0–4: header (2), total length S (2), version (1)."""
MAIN_START = PREFIX_SIZE
MAIN_SIZE = 32
"""The main frame: bytes 5–36."""
SUB_HEADER_OFFSET = MAIN_START + MAIN_SIZE
"""Byte 37: the sub frame's header (0x01 standard, 0x00 with zeros: none)."""
SUB_START = SUB_HEADER_OFFSET + 1
SUB_SIZE = 31
"""The sub frame's data: bytes 38–68."""
OPCODE_OFFSET = SUB_START + SUB_SIZE
"""Byte 69: the opcode; parameters (host) or execution status (GCU) follow."""
CRC_SIZE = 2
"""The CRC after the parameters / status: the packet's last two bytes."""
