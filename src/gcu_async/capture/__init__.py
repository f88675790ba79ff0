"""Packet captures: pcapng files of what a client or the simulator exchanges, and reading
pcap/pcapng captures back (``gcu-async decode --file``).

Needs the ``capture`` extra (``pip install 'gcu-async[capture]'``: dpkt and python-pcapng),
imported only when a capture is written or read; without it, :class:`PacketCapture` raises
:class:`CaptureUnavailable`. Open the files in Wireshark with the dissector that ships with
the package (``gcu-async wireshark --install``); see docs/wireshark.md.
"""

from gcu_async.capture._deps import CaptureUnavailable
from gcu_async.capture.blocks import CaptureError
from gcu_async.capture.reader import Record, is_capture, read_records
from gcu_async.capture.writer import (
    RAW_IP_LINKTYPE,
    SERIAL_LINKTYPE,
    PacketCapture,
    as_capture,
)

__all__ = [
    "RAW_IP_LINKTYPE", "SERIAL_LINKTYPE", "CaptureError", "CaptureUnavailable", "PacketCapture",
    "Record", "as_capture", "is_capture", "read_records",
]  # fmt: skip
