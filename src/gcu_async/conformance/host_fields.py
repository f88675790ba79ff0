"""Host check: values V2.0.6 does not define, each with what it most likely means.

Frame fields and command parameters outside their V2.0.6 range (a packet's
:attr:`~gcu_async.protocol.HostPacket.anomalies`), the version byte, unknown opcodes and
sub-frame headers; an aircraft yaw past its range (a full turn, :data:`YAW_WRAP`) read as
the signed half-turn-either-way value a host sent by mistake or as an angle not wrapped into
one turn; a parameter byte V2.0.6 gives as 0x01.
"""

from __future__ import annotations

from gcu_async.conformance.findings import Deviation, Findings
from gcu_async.protocol.anomalies import Anomaly
from gcu_async.protocol.command_decode import AnomalousCommand, UnknownCommand
from gcu_async.protocol.enums import Opcode, opcode_name
from gcu_async.protocol.gcu_frames import UnknownSubFrame
from gcu_async.protocol.host_frame_tables import AIRCRAFT_YAW
from gcu_async.protocol.host_frames import HostSubFrame
from gcu_async.protocol.packets import HostPacket, version_anomalies

_YAW = AIRCRAFT_YAW.field
_U16_SPAN = AIRCRAFT_YAW.span
YAW_WRAP = AIRCRAFT_YAW.turn
"""The raw aircraft yaw one past the field's range: a full turn
(:data:`~gcu_async.protocol.headings.TURN`)."""
YAW_SIGNED_LOW = AIRCRAFT_YAW.signed_low
"""Raw aircraft yaw values from here to the top of U16 read as S16 from minus half a turn
to one step below zero (headings west of north)."""
_SIGNED_TEXT = f"±{YAW_WRAP // 2}"
_YAW_TEXT = f"U16 [0, {YAW_WRAP})"
_TURN_TEXT = f"[0°, {YAW_WRAP / _YAW.scale:g}°)"
FIXED_PARAMETER_OPCODES = frozenset({Opcode.TAKE_PHOTO, Opcode.RECORD, Opcode.FOCUS})
"""Commands whose parameter byte V2.0.6's table gives as the constant 0x01."""
_VERSIONS = "V2.0.6 defines versions 1 and 2"


def yaw_reading(raw: int) -> str:
    """What a raw aircraft yaw value outside its range most likely means, one sentence."""
    if YAW_SIGNED_LOW <= raw < _U16_SPAN:
        signed = raw - _U16_SPAN
        return (f"reads as S16 {signed} ({signed / _YAW.scale:.2f}°): looks like a signed "
                f"{_SIGNED_TEXT} value in the {_YAW_TEXT} field")  # fmt: skip
    if YAW_WRAP <= raw < YAW_SIGNED_LOW:
        return (f"{raw / _YAW.scale:.2f}° is past 360°: looks like an angle not wrapped into "
                f"{_TURN_TEXT}")  # fmt: skip
    return ""


def field_diagnosis(anomaly: Anomaly) -> str:
    """A diagnosis of one out-of-range frame value, or ``""`` when none is recognisable."""
    if anomaly.field == "aircraft_yaw_raw":
        return yaw_reading(anomaly.value)
    if anomaly.field == "version":
        return _VERSIONS
    return ""


def frame_anomalies(packet: HostPacket) -> tuple[Anomaly, ...]:
    """The main and sub frame's anomalies (:attr:`HostMainFrame.anomalies`,
    :attr:`HostSubFrame.anomalies`), quickly when there are none: a frame whose
    ``validate()`` passes has none (both read one range table)."""
    main, sub = packet.main, packet.sub
    found: tuple[Anomaly, ...] = ()
    try:
        main.validate()
    except (TypeError, ValueError):
        found = main.anomalies
    if isinstance(sub, HostSubFrame):
        try:
            sub.validate()
        except (TypeError, ValueError):
            found += sub.anomalies
    return found


class FieldCheck:
    """Out-of-range values, unknown opcodes and sub-frame headers, by field or command."""

    def __init__(self, findings: Findings) -> None:
        self._f = findings
        self._yaw_signed = 0
        self._yaw_unwrapped = 0

    def add(self, packet: HostPacket, t: float, raw: bytes, frame: tuple[Anomaly, ...]) -> None:
        """One packet (``frame``: its :func:`frame_anomalies`)."""
        command = packet.command
        anomalies = version_anomalies(packet.version) + frame
        if isinstance(command, AnomalousCommand):
            anomalies += command.anomalies
        for anomaly in anomalies:  # packet.anomalies, in its order
            self._anomaly(packet, anomaly, t, raw)
        if isinstance(command, UnknownCommand):
            code = command.code
            params = command.params.hex(" ") or "-"
            self._f.flag(f"opcode.unknown.0x{code:02X}", f"opcode 0x{code:02X}: not in V2.0.6",
                         t, raw, f"opcode 0x{code:02X} params {params}")  # fmt: skip
        if isinstance(packet.sub, UnknownSubFrame):
            self._f.flag("sub.header", "sub frame header other than 0x01 with data", t, raw,
                         f"sub frame header 0x{packet.sub.header:02X}")  # fmt: skip

    def _anomaly(self, packet: HostPacket, a: Anomaly, t: float, raw: bytes) -> None:
        command = packet.command
        if a.field == "version":
            key, title = "version", "version byte other than 1 or 2"
        elif isinstance(command, AnomalousCommand) and a in command.anomalies:
            name = opcode_name(command.code)
            key = f"command.{name}.{a.field}"
            title = f"command 0x{command.code:02X} {name}: parameter {a.field} outside its range"
        else:
            part = "sub" if a.field in HostSubFrame._fields else "main"
            key, title = f"{part}.{a.field}", f"{a.field} outside its V2.0.6 range"
        if a.field == "aircraft_yaw_raw":
            if a.value >= YAW_SIGNED_LOW:
                self._yaw_signed += 1
            else:
                self._yaw_unwrapped += 1
        detail = f" ({a.detail})" if a.detail else ""
        extra = field_diagnosis(a)
        self._f.flag(key, title, t, raw, f"{a.field} = {a.value}, allowed {a.low}…{a.high} "
                     f"{a.unit}{detail}".rstrip() + (f"; {extra}" if extra else ""))  # fmt: skip

    def diagnose(self, devs: dict[str, Deviation], total: int) -> None:
        """Diagnoses for the report: the yaw's reading, the version, command parameters."""
        yaw = devs.get("main.aircraft_yaw_raw")
        if yaw is not None:
            share = f"aircraft yaw ≥ {YAW_WRAP} in {100 * yaw.count / total:.0f} % of packets"
            if self._yaw_signed and not self._yaw_unwrapped:
                yaw.diagnosis = (f"{share}, every one a signed S16 −{YAW_WRAP // 2}…−1 read as "
                                 f"U16: looks like a signed {_SIGNED_TEXT} value (headings "
                                 f"west of north, −180°…0°) in the {_YAW_TEXT} field")
            elif self._yaw_unwrapped and not self._yaw_signed:
                yaw.diagnosis = f"{share}: looks like an angle not wrapped into {_TURN_TEXT}"
            else:
                yaw.diagnosis = f"{share} ({self._yaw_signed} read as signed S16 values)"
        if "version" in devs:
            devs["version"].diagnosis = _VERSIONS
        for key, d in devs.items():
            if not key.startswith("command."):
                continue
            name = key.split(".")[1]
            opcode = Opcode[name] if name in Opcode.__members__ else None
            if opcode in FIXED_PARAMETER_OPCODES and key.endswith(".cameras"):
                d.diagnosis = (f"V2.0.6 gives the parameter byte of {name} as 0x01; 0x00 selects "
                               "no camera when read as a camera mask")  # fmt: skip
                if opcode == Opcode.RECORD:
                    d.diagnosis += (": looks like start/stop in the parameter byte (0x01 "
                                    "start, 0x00 stop), as ArduPilot 4.7 sends it")  # fmt: skip
            elif not d.diagnosis:
                d.diagnosis = "command parameter outside its V2.0.6 range"
