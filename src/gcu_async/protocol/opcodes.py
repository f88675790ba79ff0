"""The opcodes of V2.0.6 (byte 69 of both directions), each written once.

A command's class (:mod:`gcu_async.protocol.commands`) names its member; everything that
lists opcodes (the catalogue, the support matrix, the dissector's names) reads them from here
or from the command table.
"""

from __future__ import annotations

from enum import IntEnum

from gcu_async._checks import check_int


class Opcode(IntEnum):
    """Command opcodes of V2.0.6 (byte 69 of both directions)."""

    NULL = 0x00
    CALIBRATION = 0x01
    CENTRE = 0x03
    OSD_COORDINATES = 0x06
    IMAGE_AUTO_FLIP = 0x07
    TIME_ZONE = 0x08
    ANGLE_CONTROL = 0x10
    POINTING_LOCK = 0x11
    POINTING_FOLLOW = 0x12
    TOP_DOWN = 0x13
    EULER_CONTROL = 0x14
    GAZE_AT_COORDINATES = 0x15
    GAZE_LOCK = 0x16
    TRACK = 0x17
    CLICK_TO_PAN = 0x1A
    FPV = 0x1C
    TAKE_PHOTO = 0x20
    RECORD = 0x21
    ZOOM_IN = 0x22
    ZOOM_OUT = 0x23
    ZOOM_STOP = 0x24
    ZOOM_TO = 0x25
    FOCUS = 0x26
    PALETTE = 0x2A
    NIGHT_VISION = 0x2B
    AREA_TEMPERATURE = 0x30
    TEMPERATURE_ALARM = 0x31
    ISOTHERM = 0x32
    SPOT_TEMPERATURE = 0x33
    OSD = 0x73
    PICTURE_IN_PICTURE = 0x74
    TARGET_DETECTION = 0x75
    DIGITAL_ZOOM = 0x76
    FILL_LIGHT = 0x80
    RANGING = 0x81


_OPCODE_VALUES = frozenset(int(o) for o in Opcode)


def opcode_name(opcode: int) -> str:
    """The protocol name of ``opcode`` (``"UNKNOWN_0x42"`` for opcodes V2.0.6 does not define);
    ``opcode`` is an ``int`` 0–255 (``TypeError`` / ``FieldRangeError`` otherwise)."""
    if type(opcode) is not int or not 0 <= opcode <= 0xFF:
        opcode = check_int("opcode", opcode, 0, 0xFF)
    return Opcode(opcode).name if opcode in _OPCODE_VALUES else f"UNKNOWN_0x{opcode:02X}"
