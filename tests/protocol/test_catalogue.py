"""The command catalogue (gcu_async.protocol.catalogue) against the code it describes.

- the naming rule: method = a verb phrase, CLI name = method with dashes, class = the
  Opcode member's name in CamelCase (no ``Command`` suffix);
- every catalogue entry has its client method with the catalogue's parameters (names, order,
  defaults, kinds) and sends the entry's command class; every command method of the client
  has an entry;
- every numeric range is the one the method and the command class enforce: the bounds pass,
  the next value outside fails with a ``FieldRangeError`` naming the parameter (the class
  checks behind the method's, so a class narrower than the catalogue fails here too);
- every opcode but the null command's has an entry; the status rule agrees with
  ``read_status`` / ``failure_status``.
"""

from __future__ import annotations

import asyncio
import inspect
import math
import re
from typing import Any

import pytest

from gcu_async import GcuClient
from gcu_async.errors import FieldRangeError
from gcu_async.protocol import (
    COMMAND_TYPES,
    Command,
    ExecutionStatus,
    NullCommand,
    Opcode,
    command_code,
    failure_status,
    read_status,
)
from gcu_async.protocol.builder import build
from gcu_async.protocol.catalogue import (
    BY_METHOD,
    CATALOGUE,
    REQUIRED,
    CatalogueEntry,
    Kind,
    Parameter,
    StatusRule,
)
from helpers.client import methods as client_methods
from helpers.protocol.catalogue_samples import required_samples

VERBS = frozenset({
    "enter", "set", "take", "toggle", "start", "stop", "zoom", "focus", "calibrate", "centre",
    "track", "click", "gaze",
})  # fmt: skip
"""The verbs a command method may start with: a new method with a noun name fails."""
LEADING_ONLY = frozenset({"enter", "set", "start", "stop", "toggle"})
"""Verbs that lead: ``zoom_stop`` is a noun phrase (the verb is ``stop``, so ``stop_zoom``)."""



def command_methods() -> set[str]:
    """The client's public command methods (``execute`` takes any command: not one)."""
    return client_methods.command_methods()


def camel(name: str) -> str:
    return "".join(part.capitalize() for part in name.split("_"))


def required_kwargs(entry: CatalogueEntry) -> dict[str, Any]:
    return required_samples(entry)


async def sent(entry: CatalogueEntry, **kwargs: Any) -> list[Command]:
    """The command ``entry``'s method sends when called with ``kwargs`` (what the command
    builder the method calls makes of them)."""
    return [build(entry, **kwargs).command]


IDS = [e.method for e in CATALOGUE]


# -- the naming rule -------------------------------------------------------------------------
def test_catalogue_is_unique_and_immutable() -> None:
    assert len(BY_METHOD) == len(CATALOGUE) >= 37
    assert isinstance(CATALOGUE, tuple)
    entry = CATALOGUE[0]
    with pytest.raises(AttributeError):
        entry.method = "x"  # type: ignore[misc]
    with pytest.raises(TypeError):
        BY_METHOD["x"] = entry  # type: ignore[index]


def rule_breaks(method: str, command: type[Command]) -> list[str]:
    """How a method name and its command class break the naming rule."""
    out = []
    words = method.split("_")
    if (not re.fullmatch(r"[a-z]+(_[a-z]+)*", method) or words[0] not in VERBS
            or LEADING_ONLY.intersection(words[1:])):  # fmt: skip
        out.append(f"{method}: not a verb phrase")
    if command.__name__ != camel(command.OPCODE.name):
        out.append(f"{command.__name__}: not {camel(command.OPCODE.name)}")
    return out


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
def test_names_follow_the_rule(entry: CatalogueEntry) -> None:
    assert rule_breaks(entry.method, entry.command) == []
    assert entry.cli_name == entry.method.replace("_", "-")
    assert entry.opcode == entry.command.OPCODE
    assert entry.doc and "\n" not in entry.doc and entry.doc.endswith(".")
    assert len({p.name for p in entry.parameters}) == len(entry.parameters)


def test_every_command_class_is_named_by_its_opcode() -> None:
    for opcode, cls in COMMAND_TYPES.items():
        if cls is not NullCommand:  # "Null" alone would read as None
            assert cls.__name__ == camel(Opcode(opcode).name)
            assert not cls.__name__.endswith("Command")


def test_every_opcode_but_null_has_an_entry() -> None:
    assert {e.opcode for e in CATALOGUE} == set(Opcode) - {Opcode.NULL}
    assert {e.command for e in CATALOGUE} | {NullCommand} == set(COMMAND_TYPES.values())


@pytest.mark.parametrize("method", ["euler_control", "fpv", "pointing_lock", "zoom_stop",
                                    "area_temperature", "isotherm", "Set_osd"])  # fmt: skip
def test_the_rule_check_catches_the_old_names(method: str) -> None:
    assert rule_breaks(method, BY_METHOD["set_osd"].command) == [f"{method}: not a verb phrase"]


def test_the_rule_check_catches_a_command_suffix() -> None:
    class OsdCoordinatesCommand(BY_METHOD["set_osd_coordinates"].command):  # type: ignore[misc]
        pass

    assert rule_breaks("set_osd_coordinates", OsdCoordinatesCommand) == [
        "OsdCoordinatesCommand: not OsdCoordinates"
    ]


# -- the client against the catalogue ------------------------------------------------------
def test_every_command_method_is_catalogued() -> None:
    assert command_methods() == set(BY_METHOD)


ANNOTATIONS = {
    Kind.REAL: ("float",), Kind.INTEGER: ("int",), Kind.SWITCH: ("bool",),
    Kind.CAMERAS: ("int",), Kind.BOX: ("ImageBox", "tuple[float, float, float, float]"),
}  # fmt: skip


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
def test_method_has_the_catalogue_parameters(entry: CatalogueEntry) -> None:
    method = getattr(GcuClient, entry.method)
    assert inspect.iscoroutinefunction(method)
    params = [p for p in inspect.signature(method).parameters.values() if p.name != "self"]
    assert [p.name for p in params] == [p.name for p in entry.parameters]
    for actual, listed in zip(params, entry.parameters, strict=True):
        default = REQUIRED if actual.default is inspect.Parameter.empty else actual.default
        assert default == listed.default, f"{entry.method}({listed.name}): default"
        assert type(default) is type(listed.default), f"{entry.method}({listed.name})"
        annotation = str(actual.annotation)
        if listed.kind is Kind.CHOICE:
            assert listed.choices is not None and listed.choices.__name__ in annotation
        else:
            for part in ANNOTATIONS[listed.kind]:
                assert part in annotation, f"{entry.method}({listed.name}): {annotation}"


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
async def test_method_sends_the_entry_command(entry: CatalogueEntry) -> None:
    commands = await sent(entry, **required_kwargs(entry))
    assert [type(cmd) for cmd in commands] == [entry.command]
    assert command_code(commands[0]) == entry.opcode


def _bound_cases() -> list[tuple[CatalogueEntry, Parameter]]:
    return [(e, p) for e in CATALOGUE for p in e.parameters
            if p.kind in (Kind.REAL, Kind.INTEGER, Kind.CAMERAS)]  # fmt: skip


def _with(entry: CatalogueEntry, param: Parameter, value: float) -> dict[str, Any]:
    """The required samples, with ``value`` for ``param`` and for every parameter of the
    same range and unit (``high``/``low`` thresholds: ``low <= high`` then holds)."""
    kwargs = required_kwargs(entry)
    for p in entry.parameters:
        if (p.kind, p.unit, p.low, p.high) == (param.kind, param.unit, param.low, param.high):
            kwargs[p.name] = value
    return kwargs


def _outside(param: Parameter, bound: float, direction: float) -> float:
    if param.kind is Kind.REAL:
        return math.nextafter(bound, direction * math.inf)
    return int(bound + direction)


@pytest.mark.parametrize(("entry", "param"), _bound_cases(),
                         ids=[f"{e.method}-{p.name}" for e, p in _bound_cases()])  # fmt: skip
async def test_range_is_the_enforced_one(entry: CatalogueEntry, param: Parameter) -> None:
    assert param.low is not None and param.high is not None
    whole = param.kind is not Kind.REAL
    for bound, direction, open_ in ((param.low, -1, param.low_open),
                                    (param.high, 1, param.high_open)):  # fmt: skip
        if math.isinf(bound):
            continue
        inside = _outside(param, bound, -direction) if open_ else bound
        inside = int(inside) if whole else inside
        kwargs = _with(entry, param, inside)
        assert await sent(entry, **kwargs), (param.name, inside)
        kwargs[param.name] = bound if open_ else _outside(param, bound, direction)
        with pytest.raises(FieldRangeError, match=rf"^{param.name}\b"):
            await sent(entry, **kwargs)


@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
async def test_other_kinds_are_enforced(entry: CatalogueEntry) -> None:
    for param in entry.parameters:
        base = required_kwargs(entry)
        if param.kind is Kind.SWITCH:
            for value in (True, False):
                assert await sent(entry, **{**base, param.name: value})
            with pytest.raises(TypeError, match=param.name):
                await sent(entry, **{**base, param.name: 1})
        elif param.kind is Kind.CHOICE:
            assert param.choices is not None
            for member in param.choices:
                assert await sent(entry, **{**base, param.name: member})
            with pytest.raises(ValueError, match=param.name):
                await sent(entry, **{**base, param.name: max(param.choices) + 1})
        elif param.kind is Kind.BOX:
            assert await sent(entry, **{**base, param.name: (0.0, 0.0, 1.0, 1.0)})
            with pytest.raises(FieldRangeError, match=rf"^{param.name}\.right"):
                await sent(entry, **{**base, param.name: (0.0, 0.0, 1.5, 1.0)})


def test_range_check_can_fail() -> None:
    """A catalogue range wider than the enforced one is caught: 11 as a palette."""
    wider = Parameter("palette", Kind.INTEGER, "", "", 0, 11, default=0)
    entry = CatalogueEntry("set_palette", BY_METHOD["set_palette"].command, "x.", (wider,))
    with pytest.raises(FieldRangeError):
        asyncio.run(sent(entry, palette=11))


# -- status semantics ------------------------------------------------------------------------
@pytest.mark.parametrize("entry", CATALOGUE, ids=IDS)
def test_status_rule_agrees_with_read_status(entry: CatalogueEntry) -> None:
    op = int(entry.opcode)
    assert read_status(op, 0) is ExecutionStatus.SUCCESS
    failure = failure_status(op, 0x06)
    assert read_status(op, failure) is ExecutionStatus.FAILED
    expected = {StatusRule.ZOOM: 0x06, StatusRule.THERMAL: 0x02, StatusRule.STANDARD: 0x01,
                StatusRule.CALIBRATION: 0x01}[entry.status]  # fmt: skip
    assert failure == expected
    in_progress = read_status(op, 0x02) is ExecutionStatus.IN_PROGRESS
    assert in_progress == (entry.status is StatusRule.CALIBRATION)
