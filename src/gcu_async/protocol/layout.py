"""Facts of the packet layout that host and GCU packets share: the raw range of the signed
integer fields, and the header byte of the standard sub frame."""

from __future__ import annotations

S16 = (-(2**15), 2**15 - 1)
"""Raw range of a signed 16-bit field (little-endian on the wire)."""
S32 = (-(2**31), 2**31 - 1)
"""Raw range of a signed 32-bit field (little-endian on the wire)."""
SUB_FRAME_HEADER = 0x01
"""Byte 37 of a standard sub frame, in either direction (the only one V2.0.6 defines)."""
