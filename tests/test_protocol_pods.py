"""Pod models (Appendix 7) and the command support matrix (Appendix 8), checked against the
tables of the protocol document itself."""

from __future__ import annotations

import pytest

from _vectors import spec_text
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

# Appendix 8 row labels → opcodes
ROW_OPCODES = {
    "跟踪": Opcode.TRACK,
    "OSD 坐标": Opcode.OSD_COORDINATES,
    "图像自动翻转": Opcode.IMAGE_AUTO_FLIP,
    "时区": Opcode.TIME_ZONE,
    "指定倍率": Opcode.ZOOM_TO,
    "聚焦": Opcode.FOCUS,
    "调色盘": Opcode.PALETTE,
    "夜视": Opcode.NIGHT_VISION,
    "区域测温": Opcode.AREA_TEMPERATURE,
    "温度报警": Opcode.TEMPERATURE_ALARM,
    "等温线": Opcode.ISOTHERM,
    "指点测温": Opcode.SPOT_TEMPERATURE,
    "OSD": Opcode.OSD,
    "画中画": Opcode.PICTURE_IN_PICTURE,
    "目标识别": Opcode.TARGET_DETECTION,
    "数字变焦": Opcode.DIGITAL_ZOOM,
    "补光": Opcode.FILL_LIGHT,
    "连续测距": Opcode.RANGING,
}
THERMAL_ONLY = {
    Opcode.AREA_TEMPERATURE,
    Opcode.TEMPERATURE_ALARM,
    Opcode.ISOTHERM,
    Opcode.SPOT_TEMPERATURE,
}


def _section(title: str) -> str:
    text = spec_text()
    start = text.index(f"## {title}")
    end = text.find("\n## ", start + 1)
    return text[start : end if end >= 0 else len(text)]


def appendix7() -> dict[int, str]:
    """Code → model name, parsed from the document's Appendix 7 table."""
    table = {}
    for line in _section("附录 7").splitlines():
        cells = line.split("\t")
        if len(cells) == 2 and cells[0].strip().isdigit():
            table[int(cells[0])] = cells[1].strip()
    return table


def appendix8() -> dict[tuple[str, Opcode], bool]:
    """(model name, opcode) → supported (● / ○), parsed from the document's Appendix 8."""
    table: dict[tuple[str, Opcode], bool] = {}
    models: list[str] = []
    for line in _section("附录 8").splitlines():
        cells = [c.strip() for c in line.split("\t")]
        if cells[0] == "命令":
            models = cells[1:]
        elif cells[0] in ROW_OPCODES:
            assert len(cells) == len(models) + 1, line
            for model, mark in zip(models, cells[1:], strict=True):
                assert mark in ("●", "○"), mark
                table[(model, ROW_OPCODES[cells[0]])] = mark == "●"
    return table


def test_parsed_tables_are_complete() -> None:
    assert len(appendix7()) == 20
    assert len(appendix8()) == 20 * 18


def test_every_appendix7_code_has_a_name_and_a_matrix_row() -> None:
    table = appendix7()
    listed = {m for m in PodModel if m is not PodModel.UNKNOWN}
    assert {int(m) for m in listed} == set(table)
    assert set(POD_NAMES) == listed == set(SUPPORT)
    for code, name in table.items():
        assert pod_name(code) == name
        assert resolve_pod_model(name) == PodModel(code)
        assert len(SUPPORT[PodModel(code)]) <= len(MATRIX_COMMANDS)


def test_matrix_equals_appendix8_cell_by_cell() -> None:
    assert set(MATRIX_COMMANDS) == set(ROW_OPCODES.values())
    for (model, opcode), supported in appendix8().items():
        assert supports(model, opcode) is supported, (model, opcode.name)


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
