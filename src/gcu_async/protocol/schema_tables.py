"""The command schema as plain tables, for table-driven decoders such as the Wireshark
dissector's generator: every opcode's parameter fields in wire order (struct code, scale, unit,
raw range, enum). Made from :mod:`gcu_async.protocol.commands`; nothing is written here.

Every command's parameter bytes have a fixed length: the sum of its fields' sizes.
"""

from gcu_async.protocol.commands import WireParam, WireRow, wire_rows

__all__ = ["WireParam", "WireRow", "wire_rows"]
