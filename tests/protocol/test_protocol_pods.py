"""Pod models (Appendix 7) and the command support matrix (Appendix 8), checked against the
repository's own transcription of the document's tables (tests/data/pod-*.csv)."""

from __future__ import annotations

import pytest

from gcu_async.protocol import (
    POD_NAMES,
    Opcode,
    PodModel,
    is_radiometric,
    is_thermal,
    pod_name,
    resolve_pod_model,
    supports,
)
from gcu_async.protocol.pods import MATRIX_COMMANDS, SUPPORT
from helpers.protocol.vectors import pod_models, pod_support

THERMAL_ONLY = {
    Opcode.AREA_TEMPERATURE,
    Opcode.TEMPERATURE_ALARM,
    Opcode.ISOTHERM,
    Opcode.SPOT_TEMPERATURE,
}


def test_transcribed_tables_are_complete() -> None:
    models = pod_models()
    commands, matrix = pod_support()
    assert len(models) == 20
    assert len(commands) == len(set(commands)) == 18
    assert len(matrix) == 20 * 18
    # Appendix 8 names the same models as Appendix 7, in the same order
    assert list(dict.fromkeys(model for model, _ in matrix)) == list(models.values())


def test_every_appendix7_code_has_a_name_and_a_matrix_row() -> None:
    table = pod_models()
    listed = {m for m in PodModel if m is not PodModel.UNKNOWN}
    assert {int(m) for m in listed} == set(table)
    assert set(POD_NAMES) == listed == set(SUPPORT)
    for code, name in table.items():
        assert pod_name(code) == name
        assert resolve_pod_model(name) == PodModel(code)
        assert len(SUPPORT[PodModel(code)]) <= len(MATRIX_COMMANDS)


def test_matrix_equals_appendix8_cell_by_cell() -> None:
    commands, matrix = pod_support()
    assert [op.name for op in MATRIX_COMMANDS] == commands  # the document's row order
    for (model, command), supported in matrix.items():
        assert supports(model, Opcode[command]) is supported, (model, command)


@pytest.mark.parametrize(
    ("model", "opcode", "expected"),
    [
        ("Z-6A", Opcode.ZOOM_TO, False),
        ("D-80AI", Opcode.ZOOM_TO, True),
        ("D-90Pro(T)", Opcode.TRACK, False),
        ("D-90Pro(VA)", Opcode.TRACK, True),
        ("Z-6C", Opcode.TRACK, False),
        ("Z-8RB", Opcode.RANGING, True),
        ("D-80AI", Opcode.RANGING, False),
        ("D-90Pro(TA)", Opcode.FILL_LIGHT, False),
        ("D-80Pro", Opcode.FILL_LIGHT, True),
        ("Z-1Pro", Opcode.FOCUS, False),
        ("Z-9B_V3", Opcode.PALETTE, True),
    ],
)
def test_appendix8_spot_checks(model: str, opcode: Opcode, expected: bool) -> None:
    assert supports(model, opcode) is expected


def test_z9b_v4_t_supports_everything() -> None:
    assert all(supports("Z-9B_V4(T)", op) for op in Opcode)
    assert SUPPORT[PodModel.Z_9B_V4_T] == frozenset(MATRIX_COMMANDS)


@pytest.mark.parametrize(
    "opcode", [op for op in Opcode if op not in MATRIX_COMMANDS], ids=lambda o: o.name
)
def test_commands_not_in_appendix8_supported_by_all(opcode: Opcode) -> None:
    assert all(supports(model, opcode) for model in POD_NAMES)


def test_take_photo_and_unknown_opcodes_supported_by_all() -> None:
    assert all(supports(m, Opcode.TAKE_PHOTO) for m in POD_NAMES)
    assert supports(PodModel.Z_6A, 0x99)


def test_thermal_commands_only_on_radiometric_models() -> None:
    for model in POD_NAMES:
        assert {supports(model, op) for op in THERMAL_ONLY} == {is_radiometric(model)}
        assert is_thermal(model) == supports(model, Opcode.PALETTE)
    assert is_radiometric("D-90Pro(T)")
    assert not is_radiometric("D-90Pro(V)")
    assert not is_thermal("Z-6A")
    assert is_thermal("D-90AI")


@pytest.mark.parametrize(
    "spelling",
    [
        "D-90Pro(TA)",
        "d-90pro(ta)",
        "D_90PRO_TA",
        "d90prota",
        " D-90Pro(TA) ",
        "45",
        45,
        PodModel.D_90PRO_TA,
    ],
)
def test_resolve_pod_model(spelling: object) -> None:
    assert resolve_pod_model(spelling) is PodModel.D_90PRO_TA  # type: ignore[arg-type]


def test_similar_names_resolve_to_different_models() -> None:
    assert resolve_pod_model("D-90Pro(T)") is PodModel.D_90PRO_T
    assert resolve_pod_model("Z-9B_V4(V)") is PodModel.Z_9B_V4_V
    assert resolve_pod_model("Z-6A") is PodModel.Z_6A
    assert resolve_pod_model(0) is PodModel.Z_6A


@pytest.mark.parametrize("bad", ["D-99", "", "Z-6", "Pro"])
def test_bad_name_is_a_value_error_listing_models(bad: str) -> None:
    with pytest.raises(ValueError, match=r"pod model: .* is not one of Z-6A, .*D-90Pro\(V\)"):
        resolve_pod_model(bad)


@pytest.mark.parametrize("code", [1, 99, 255, "1", PodModel.UNKNOWN])
def test_unlisted_code_is_a_value_error(code: object) -> None:
    with pytest.raises(ValueError, match="not listed in Appendix 7"):
        resolve_pod_model(code)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="not listed in Appendix 7"):
        supports(code, Opcode.TRACK)  # type: ignore[arg-type]


def test_pod_name_of_unlisted_code() -> None:
    assert pod_name(99) == "unknown (code 99)"
    assert PodModel(99) is PodModel.UNKNOWN
