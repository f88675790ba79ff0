"""The wire logger: every packet in and out, at DEBUG on the ``gcu_async.wire`` logger
(docs/client.md, "Logging").

Each line is the direction, the packet's hex and a one-line decode::

    gcu_async.wire DEBUG udp://192.168.144.108:2337 > 8a5e4c02… | TAKE_PHOTO 01 | control invalid
    gcu_async.wire DEBUG udp://192.168.144.108:2337 < 8a5e4902… | fb TAKE_PHOTO SUCCESS | …

The client checks ``WIRE_LOG.isEnabledFor(logging.DEBUG)`` on every heartbeat tick, so the
level can change at run time; nothing is formatted while it is off.
"""

from __future__ import annotations

import logging

from gcu_async.errors import RemoteProtocolError
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_decode import AnomalousCommand, command_code
from gcu_async.protocol.gcu_frames import GcuSubFrame
from gcu_async.protocol.packets import decode_gcu_packet, decode_host_packet

WIRE_LOG = logging.getLogger("gcu_async.wire")


def describe_host(data: bytes) -> str:
    """One line for a host → GCU packet: command (opcode name and parameter bytes), whether
    the control values are valid, the aircraft INS flag."""
    try:
        packet = decode_host_packet(data)
    except RemoteProtocolError as exc:
        return f"undecodable: {exc}"
    command = packet.command
    params = command.params if isinstance(command, AnomalousCommand) else command.encode_params()
    name = command.as_dict()["command"]
    what = f"{name} {params.hex()}" if params else name
    main = packet.main
    if main.control_valid:
        r, p, y = main.control
        control = f"control valid {r} {p} {y}"
    else:
        control = "control invalid"
    ins = "ins valid" if main.ins_valid else "ins invalid"
    line = f"{what} (0x{command_code(command):02x}) | {control} | {ins} | v{packet.version}"
    return line + _flags(packet.anomalies)


def describe_gcu(data: bytes) -> str:
    """One line for a GCU → host packet: the feedback, the mode, the camera attitude and,
    with a sub frame, the zoom."""
    try:
        packet = decode_gcu_packet(data)
    except RemoteProtocolError as exc:
        return f"undecodable: {exc}"
    fb = packet.feedback
    status = "" if fb.status is None else f" {fb.result.name}"
    main = packet.main
    a = main.attitude
    line = (f"fb {fb.command}{status} | mode {main.mode.name} | att r{a.roll:+.2f} "
            f"p{a.pitch:+.2f} y{a.yaw:.2f}")  # fmt: skip
    if type(packet.sub) is GcuSubFrame:
        line += f" | zoom {packet.sub.camera1_zoom:.1f}x"
    return f"{line} | v{packet.version}{_flags(packet.anomalies)}"


def _flags(anomalies: tuple[Anomaly, ...]) -> str:
    """The anomalies of a decoded packet (docs/client.md, "Liberal receive, strict send")."""
    return "".join(f" | flagged: {a}" for a in anomalies)


def log_packet(url: str, outgoing: bool, data: bytes) -> None:
    """Log one packet at DEBUG (call only when ``WIRE_LOG`` is enabled for DEBUG)."""
    line = describe_host(data) if outgoing else describe_gcu(data)
    WIRE_LOG.debug("%s %s %s | %s", url, ">" if outgoing else "<", data.hex(), line)


__all__ = ["WIRE_LOG", "describe_gcu", "describe_host", "log_packet"]
