"""Negative numbers on the command line: every value that can be negative parses, as an
argument or an option's value, with or without ``=`` (southern and western coordinates,
negative rates and angles, exponents). Parsing only: nothing is opened."""

from __future__ import annotations

import argparse
import contextlib
import math

import pytest

from gcu_async.cli import build_parser
from gcu_async.cli.send import resolve
from gcu_async.cli.send_commands import COMMANDS, AircraftFix
from gcu_async.protocol.catalogue import CATALOGUE, Kind, Parameter
from helpers.protocol.catalogue_samples import sample

URL = "udp://127.0.0.1:9"
AIRCRAFT = "-33.85,-151.2,-5,-90"
"""South, west, below sea level, heading west: every part negative."""


def _negative(p: Parameter) -> tuple[str, float]:
    """A negative value inside ``p``'s range, as typed on a command line (an exponent for a
    real), and the value it means."""
    assert p.low is not None and p.high is not None
    if p.kind is Kind.INTEGER:
        return "-1", -1
    value = max(p.low / 2, -1.0) if math.isfinite(p.low) else -1.0
    return f"{value:e}", float(f"{value:e}")


def _can_be_negative(p: Parameter) -> bool:
    return p.kind in (Kind.REAL, Kind.INTEGER) and p.low is not None and p.low < 0


NEGATIVE = sorted({entry.cli_name for entry in CATALOGUE for p in entry.parameters
                   if _can_be_negative(p) and p.name in {q.name for q in
                                                         COMMANDS[entry.cli_name].params}})
"""The ``send`` commands with an argument that can be negative."""


def test_some_command_arguments_can_be_negative() -> None:
    assert len(NEGATIVE) >= 10  # angles, rates, coordinates, temperatures, the time zone


def _parse(argv: list[str]) -> argparse.Namespace:
    args = build_parser().parse_args(["send", *argv])
    resolve(args)
    return args


@pytest.mark.parametrize("name", NEGATIVE)
def test_negative_command_arguments_are_values(name: str) -> None:
    """Every argument of the command that can be negative is given a negative value (an
    exponent for a real), the others a sample; each parses to its number."""
    entry = next(e for e in CATALOGUE if e.cli_name == name)
    by_name = {p.name: p for p in entry.parameters}
    params = COMMANDS[name].params
    last = max(i for i, q in enumerate(params) if q.name in by_name
               and _can_be_negative(by_name[q.name]))
    texts: list[str] = []
    expected: dict[str, float] = {}
    for q in params[:last + 1]:
        p = by_name.get(q.name)
        if p is not None and _can_be_negative(p):
            text, expected[q.name] = _negative(p)
        else:  # a box edge (the box is four arguments) or a non-negative parameter
            text = "0.5" if p is None else str(sample(p))
        texts.append(text)
    aircraft = ["--aircraft", AIRCRAFT] if COMMANDS[name].needs_ins else []
    args = _parse([URL, name, *texts, *aircraft])
    assert {n: getattr(args, f"arg_{n}") for n in expected} == expected


@pytest.mark.parametrize("where", ["before", "after"])
@pytest.mark.parametrize("form", ["space", "equals"])
def test_aircraft_with_negative_coordinates(where: str, form: str) -> None:
    option = ["--aircraft", AIRCRAFT] if form == "space" else [f"--aircraft={AIRCRAFT}"]
    command = ["gaze-at", "-33.86", "-151.21", "-1e1"]
    argv = [URL, *option, *command] if where == "before" else [URL, *command, *option]
    args = _parse(argv)
    assert args.aircraft == AircraftFix(-33.85, -151.2, -5.0, -90.0)
    assert (args.arg_latitude, args.arg_longitude, args.arg_altitude) == (-33.86, -151.21, -10.0)


def _value_options(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    return [a for a in parser._actions if a.option_strings and a.nargs is None
            and isinstance(a, argparse._StoreAction)]


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


@pytest.mark.parametrize("name", sorted(_subparsers()))
def test_no_option_value_is_taken_for_an_option(name: str,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    """Every option of every sub-command that takes a value accepts one starting with a
    minus: the check that follows may refuse it, argparse never reads it as an option."""
    parser = _subparsers()[name]
    positionals = ["x" for a in parser._actions
                   if not a.option_strings and a.nargs not in ("*", "?", argparse.REMAINDER)]
    required = [arg for a in parser._actions if a.option_strings and a.required
                for arg in (a.option_strings[-1], "x")]
    options = _value_options(parser)
    assert options, name
    for action in options:
        for text in ("-1.5e0", "-2,-3"):
            with contextlib.suppress(SystemExit):  # a type or choice error: not ours
                parser.parse_known_args([*required, action.option_strings[-1], text,
                                         *positionals])
            assert "expected one argument" not in capsys.readouterr().err, action.option_strings


@pytest.mark.parametrize("form", [["--pitch", "-45"], ["--pitch=-45"]])
def test_an_optional_argument_by_name_alone(form: list[str]) -> None:
    """``enter-euler-control --pitch -45``: pitch alone, roll and yaw left to the camera's."""
    args = build_parser().parse_args(["send", URL, "enter-euler-control", *form])
    inv = resolve(args)
    assert inv.values == [] and inv.named == {"pitch": -45.0}
    assert inv.spec.build(inv.values, inv.named)[1] == {"pitch": -45.0}


def test_an_argument_given_twice_is_refused() -> None:
    args = build_parser().parse_args(["send", URL, "enter-euler-control", "5", "--roll", "6"])
    with pytest.raises(ValueError, match=r"^roll: given twice"):
        resolve(args)
