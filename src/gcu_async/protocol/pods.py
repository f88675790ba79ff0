"""Pod models (Appendix 7) and which commands each supports (Appendix 8).

Appendix 8 lists 18 commands (:data:`MATRIX_COMMANDS`, by opcode: this module needs nothing
of the command table); commands it does not list are supported by every model.
"""

from __future__ import annotations

from gcu_async._checks import check_int, type_error
from gcu_async.protocol.enums import PodModel
from gcu_async.protocol.opcodes import Opcode

MATRIX_COMMANDS: tuple[Opcode, ...] = (
    Opcode.TRACK, Opcode.OSD_COORDINATES, Opcode.IMAGE_AUTO_FLIP, Opcode.TIME_ZONE,
    Opcode.ZOOM_TO, Opcode.FOCUS, Opcode.PALETTE, Opcode.NIGHT_VISION, Opcode.AREA_TEMPERATURE,
    Opcode.TEMPERATURE_ALARM, Opcode.ISOTHERM, Opcode.SPOT_TEMPERATURE, Opcode.OSD,
    Opcode.PICTURE_IN_PICTURE, Opcode.TARGET_DETECTION, Opcode.DIGITAL_ZOOM, Opcode.FILL_LIGHT,
    Opcode.RANGING,
)
"""The rows of Appendix 8, in the document's order."""

# Each model: its vendor spelling ((T) thermometric, (V) observation, (TA)/(VA) + AI core)
# and its Appendix 8 column, one character per MATRIX_COMMANDS row: 1 = ● supported, 0 = ○.
_PODS: dict[PodModel, tuple[str, str]] = {
    PodModel.Z_6A:       ("Z-6A",         "100001010000000000"),
    PodModel.Z_6C:       ("Z-6C",         "000001010000000000"),
    PodModel.Z_8RB:      ("Z-8RB",        "100001010000000001"),
    PodModel.Z_8RC:      ("Z-8RC",        "000001010000000001"),
    PodModel.Z_9B_V3:    ("Z-9B_V3",      "100001110000010011"),
    PodModel.D_80AI:     ("D-80AI",       "100011010000110010"),
    PodModel.D_90AI:     ("D-90AI",       "100011110000110001"),
    PodModel.D_80PRO:    ("D-80Pro",      "100011010000000010"),
    PodModel.D_90PRO_TA: ("D-90Pro(TA)",  "111111111111111101"),
    PodModel.Z_1PRO:     ("Z-1Pro",       "111110000000101000"),
    PodModel.Z_1MINI:    ("Z-1Mini",      "111110000000101000"),
    PodModel.Z_2MINI:    ("Z-2Mini",      "111110100000111000"),
    PodModel.D_125AI_T:  ("D-125AI(T)",   "111111111111111101"),
    PodModel.D_90DE:     ("D-90DE",       "100011010000110001"),
    PodModel.D_125AI_V:  ("D-125AI(V)",   "111111110000111101"),
    PodModel.Z_9B_V4_T:  ("Z-9B_V4(T)",   "111111111111111111"),
    PodModel.Z_9B_V4_V:  ("Z-9B_V4(V)",   "111111110000111111"),
    PodModel.D_90PRO_VA: ("D-90Pro(VA)",  "111111110000111101"),
    PodModel.D_90PRO_T:  ("D-90Pro(T)",   "011111111111110101"),
    PodModel.D_90PRO_V:  ("D-90Pro(V)",   "011111110000110101"),
}  # fmt: skip

POD_NAMES: dict[PodModel, str] = {model: name for model, (name, _) in _PODS.items()}
"""Vendor spelling of each model (Appendix 7)."""

SUPPORT: dict[PodModel, frozenset[Opcode]] = {
    model: frozenset(op for op, bit in zip(MATRIX_COMMANDS, row, strict=True) if bit == "1")
    for model, (_, row) in _PODS.items()
}
"""For each model, the Appendix 8 commands it supports."""


def supports(model: PodModel | int | str, opcode: Opcode | int) -> bool:
    """Does ``model`` support ``opcode`` (an ``int`` 0–255)? Commands Appendix 8 does not
    list, unknown opcodes included: always.

    Raises ``ValueError`` for a model Appendix 7 does not list (support is unknown).
    """
    pod = resolve_pod_model(model)
    check_int("opcode", opcode, 0, 0xFF)
    if opcode not in MATRIX_COMMANDS:
        return True
    return Opcode(opcode) in SUPPORT[pod]


def is_thermal(model: PodModel | int | str) -> bool:
    """Has a thermal camera (the palette command is supported)."""
    return Opcode.PALETTE in SUPPORT[resolve_pod_model(model)]


def is_radiometric(model: PodModel | int | str) -> bool:
    """Measures temperature (the area-temperature command is supported)."""
    return Opcode.AREA_TEMPERATURE in SUPPORT[resolve_pod_model(model)]


def pod_name(model: PodModel | int) -> str:
    """Vendor spelling of a model code (``"unknown (code 99)"`` for unlisted codes): a
    :class:`PodModel` member or a code 0–255 (what the wire carries)."""
    if not isinstance(model, PodModel):
        model = check_int("pod model", model, 0, 0xFF)
    pod = PodModel(model)
    return POD_NAMES.get(pod, f"unknown (code {int(model)})")


def resolve_pod_model(model: PodModel | int | str) -> PodModel:
    """A :class:`PodModel` from a member, an Appendix 7 code, or a name (``"D-90Pro(TA)"``,
    ``"d_90pro_ta"`` or ``"45"``). Raises ``ValueError`` naming the known models or codes,
    ``TypeError`` for anything but a ``str`` or an ``int`` (bools and floats included)."""
    if isinstance(model, str):
        key = _norm(model)
        for pod, name in POD_NAMES.items():
            if key in (_norm(name), _norm(pod.name)):
                return pod
        digits = model.strip()
        if digits.isascii() and digits.isdigit():
            model = int(digits)
        else:
            raise ValueError(f"pod model: {model!r} is not one of {', '.join(POD_NAMES.values())}")
    elif isinstance(model, bool) or not isinstance(model, int):
        raise type_error("pod model", "a PodModel, its code (int) or its name (str)", model)
    pod = PodModel(model)
    if pod not in POD_NAMES:
        codes = ", ".join(str(int(p)) for p in POD_NAMES)
        raise ValueError(f"pod model: code {int(model)} is not listed in Appendix 7 "
                         f"(listed: {codes})")  # fmt: skip
    return pod


def _norm(text: str) -> str:
    return "".join(ch for ch in text.lower() if ch.isalnum())
