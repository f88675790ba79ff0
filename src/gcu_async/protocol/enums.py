"""Modes, pod models and every bit field of the protocol (opcodes: re-exported from
:mod:`gcu_async.protocol.opcodes`).

Enums carry the protocol's own names; unknown raw values map to an ``UNKNOWN`` member so
decoding never fails on a newer firmware (the raw integer always stays on the frame).
"""

from __future__ import annotations

from enum import IntEnum, IntFlag
from typing import Any

from gcu_async.protocol.opcodes import Opcode as Opcode
from gcu_async.protocol.opcodes import opcode_name as opcode_name


class _UnknownIfUnlisted:
    """Enum mixin: a value the enum does not list is its ``UNKNOWN`` member (decoding is
    liberal: a new mode or pod model on the wire is not an error)."""

    @classmethod
    def _missing_(cls, value: object) -> Any:
        return cls.__members__["UNKNOWN"]  # type: ignore[attr-defined]


class Mode(_UnknownIfUnlisted, IntEnum):
    """Pod working mode (GCU main frame byte 5)."""

    UNKNOWN = -1
    ANGLE_CONTROL = 0x10
    POINTING_LOCK = 0x11
    POINTING_FOLLOW = 0x12
    TOP_DOWN = 0x13
    EULER_CONTROL = 0x14
    GAZE = 0x16
    TRACK = 0x17
    FPV = 0x1C


class PodModel(_UnknownIfUnlisted, IntEnum):
    """Pod model codes (Appendix 7). Use :func:`gcu_async.protocol.pods.pod_name` for the
    vendor's spelling (``"D-90Pro(TA)"``)."""

    UNKNOWN = -1
    Z_6A = 0
    Z_6C = 2
    Z_8RB = 25
    Z_8RC = 26
    Z_9B_V3 = 31
    D_80AI = 40
    D_90AI = 41
    D_80PRO = 44
    D_90PRO_TA = 45
    Z_1PRO = 49
    Z_1MINI = 50
    Z_2MINI = 52
    D_125AI_T = 53
    D_90DE = 55
    D_125AI_V = 57
    Z_9B_V4_T = 58
    Z_9B_V4_V = 59
    D_90PRO_VA = 60
    D_90PRO_T = 61
    D_90PRO_V = 62


class HostFlags(IntFlag):
    """Host main frame byte 11 (B7–B3 and B1 reserved, must be 0)."""

    INS_VALID = 1 << 0
    CONTROL_VALID = 1 << 2


class PodStatus(IntFlag):
    """GCU main frame bytes 6–7, read little-endian (docs/protocol-notes.md §1 "Byte order of the
    pod-status example": the vendor example contradicts its own byte-order rule; the library follows
    the rule)."""

    TRACKING_OK = 1 << 0
    RANGE_VALID = 1 << 7
    RANGING_ON = 1 << 8
    NIGHT_VISION_ON = 1 << 9
    FILL_LIGHT_ON = 1 << 10
    INVERTED = 1 << 12


class FaultFlags(IntFlag):
    """GCU sub frame bytes 41–42: fault code."""

    POD_HARDWARE = 1 << 7
    MAVLINK_RATE = 1 << 13
    GNSS_NO_FIX = 1 << 14
    GCU_HARDWARE = 1 << 15


class ThermalFlags(IntFlag):
    """GCU sub frame byte 63: thermal camera status."""

    LOW_TEMPERATURE_ALARM = 1 << 0
    HIGH_TEMPERATURE_ALARM = 1 << 1
    SPOT_TEMPERATURE_ON = 1 << 3
    ISOTHERM_ON = 1 << 4
    TEMPERATURE_ALARM_ON = 1 << 5
    AREA_TEMPERATURE_ON = 1 << 6
    MEASUREMENT_AVAILABLE = 1 << 7


class CameraFlags(IntFlag):
    """GCU sub frame bytes 64–65: camera status. Bits 2–0 hold the picture-in-picture mode
    (a number, see ``GcuSubFrame.pip_mode``), so they are not members here."""

    RECORDING = 1 << 4
    AUTO_FLIP_OFF = 1 << 11
    OSD_TARGET_COORDINATES = 1 << 12
    OSD_ON = 1 << 13
    DIGITAL_ZOOM_ON = 1 << 14
    TARGET_DETECTION_ON = 1 << 15


PIP_MODE_MASK = 0x07


class CameraMask(IntFlag):
    """Camera selection byte (KK / NN in the spec): bit 0 = camera 1 (visible / zoom by
    default) … bit 7 = camera 8."""

    CAMERA_1 = 1 << 0
    CAMERA_2 = 1 << 1
    CAMERA_3 = 1 << 2
    CAMERA_4 = 1 << 3
    CAMERA_5 = 1 << 4
    CAMERA_6 = 1 << 5
    CAMERA_7 = 1 << 6
    CAMERA_8 = 1 << 7

    VISIBLE = CAMERA_1
    THERMAL = CAMERA_2


class ExecutionStatus(IntEnum):
    """Meaning of a feedback's execution status, read per command (docs/protocol-notes.md
    §2 "Execution status per command")."""

    NONE = 0
    """The reply carried no execution status (e.g. feedback to the null command)."""
    SUCCESS = 1
    FAILED = 2
    IN_PROGRESS = 3


class NightVisionMode(IntEnum):
    """Night vision command (:class:`~gcu_async.protocol.commands.NightVision`) parameter TT."""

    OFF = 0
    ON = 1
    AUTO = 2


class OsdCoordinateSource(IntEnum):
    """OSD coordinate command (0x06) parameter TT."""

    AIRCRAFT = 0
    TARGET = 1


class SubFrameRequest(IntEnum):
    """Host main frame byte 30: which GCU sub frame to send back."""

    NONE = 0x00
    STANDARD = 0x01

