"""Where a GCU is reached: its UDP and TCP ports and its serial rates.

Defined once here (docs/protocol-notes.md §12 "Transports") and shared by the client's
transports (:mod:`gcu_async.transport`) and the simulator's servers (:mod:`gcu_async.sim`).
"""

from __future__ import annotations

GCU_UDP_PORT = 2337
"""Port the GCU listens on for UDP (docs/protocol-notes.md §12 "Transports")."""
HOST_UDP_PORT = 2338
"""Port the host listens on; the GCU broadcasts to it (docs/protocol-notes.md §12 "Transports")."""
GCU_TCP_PORT = 2332
"""Port the GCU's TCP server listens on (docs/protocol-notes.md §12 "Transports")."""
BAUDRATES = (115200, 250000, 500000, 1000000)
"""The serial rates a GCU auto-detects, 8N1 (docs/protocol-notes.md §12 "Transports")."""
DEFAULT_BAUDRATE = 115200
"""The serial rate used when none is given (one of :data:`BAUDRATES`)."""
