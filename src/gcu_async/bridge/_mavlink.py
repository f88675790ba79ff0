"""The one place pymavlink is imported: MAVLink 2 framing, the ``ardupilotmega`` dialect.

pymavlink picks its wire version when :mod:`pymavlink.mavutil` is first imported (the
``MAVLINK20`` environment variable). This module sets ``MAVLINK20=1`` before that import
and, if something imported :mod:`~pymavlink.mavutil` earlier without it, switches the
dialect to MAVLink 2 again, so every connection the bridge opens parses and sends MAVLink 2.
The dialect is ``ardupilotmega`` (pymavlink's default; it includes ``common``, the gimbal
and camera protocols among it), so the bridge talks to ArduPilot and PX4 alike.
"""

from __future__ import annotations

import os
from typing import Any

os.environ.setdefault("MAVLINK20", "1")

try:
    from pymavlink import mavutil
    from pymavlink.dialects.v20 import ardupilotmega as mavlink
except ImportError as exc:  # pragma: no cover - the extra is installed in every test venv
    raise ImportError(
        "gcu_async.bridge needs pymavlink: pip install 'gcu-async[mavlink]'"
    ) from exc

if getattr(mavutil.mavlink, "WIRE_PROTOCOL_VERSION", "2.0") != "2.0":  # pragma: no cover
    os.environ["MAVLINK20"] = "1"
    mavutil.set_dialect(mavutil.current_dialect)


def new_parser() -> Any:
    """A parser for one peer's bytes: invalid input comes out as ``BAD_DATA`` messages
    (pymavlink's robust parsing) instead of exceptions."""
    parser = mavlink.MAVLink(None)
    parser.robust_parsing = True
    return parser


__all__ = ["mavlink", "mavutil", "new_parser"]
