"""The commands of ``gcu-async send``: one per entry of the command catalogue
(:mod:`gcu_async.protocol.catalogue`), named as its method with dashes, with the arguments
each takes on the command line (units and ranges for its ``--help``, from the catalogue) and
how they map onto the method's parameters (docs/cli.md, "gcu-async send")."""

from __future__ import annotations

import argparse
import inspect
import itertools
import re
import textwrap
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, NamedTuple

from gcu_async.client.client import GcuClient
from gcu_async.protocol import builder
from gcu_async.protocol.catalogue import CATALOGUE, CatalogueEntry, Kind, Parameter
from gcu_async.protocol.command_fields import IMAGE_SCALE
from gcu_async.protocol.enums import CameraMask
from gcu_async.protocol.units import ImageBox


def _switch(text: str) -> bool:
    value = text.strip().lower()
    if value in ("on", "1", "true", "yes", "enable"):
        return True
    if value in ("off", "0", "false", "no", "disable"):
        return False
    raise argparse.ArgumentTypeError(f"expected on/off, got {text!r}")


def _choice(choices: type[IntEnum]) -> Callable[[str], IntEnum]:
    """A converter of a member name (any case) of ``choices``."""
    names = "/".join(m.name.lower() for m in choices)

    def convert(text: str) -> IntEnum:
        try:
            return choices[text.strip().upper()]
        except KeyError:
            raise argparse.ArgumentTypeError(f"expected {names}, got {text!r}") from None

    return convert


CAMERA_NAMES: dict[str, CameraMask] = {
    **{f"camera_{n}": CameraMask(1 << (n - 1)) for n in range(1, 9)},
    "visible": CameraMask.VISIBLE,
    "thermal": CameraMask.THERMAL,
}
"""Names ``--cameras`` takes besides the camera numbers 1–8 (:class:`CameraMask`)."""


class AircraftFix(NamedTuple):
    """``send --aircraft``: an aircraft standing still, level, at a position and heading."""

    latitude: float
    longitude: float
    altitude: float
    """Metres above mean sea level."""
    yaw: float = 0.0
    """Heading, degrees (north = 0; signed or compass, as
    :data:`~gcu_async.protocol.units.YAW_INPUT_RANGE` allows)."""

    def state(self) -> dict[str, Any]:
        """The keyword arguments of :meth:`GcuClient.update_aircraft` that claim it."""
        return {"attitude": (0.0, 0.0, self.yaw), "acceleration": (0.0, 0.0, 0.0),
                "velocity": (0.0, 0.0, 0.0),
                "position": (self.latitude, self.longitude, self.altitude)}  # fmt: skip


def parse_aircraft(text: str) -> AircraftFix:
    """``LAT,LON,ALT[,YAW]`` (degrees, degrees, metres MSL, degrees) as an
    :class:`AircraftFix`; the ranges are checked by ``update_aircraft`` itself."""
    items = text.split(",")
    try:
        if len(items) not in (3, 4):
            raise ValueError
        return AircraftFix(*(float(item) for item in items))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected LAT,LON,ALT[,YAW] (degrees, degrees, metres MSL, degrees), got {text!r}"
        ) from None


def parse_cameras(text: str) -> CameraMask:
    """The camera mask (``cameras=`` of the client's methods) from a comma-separated list
    of camera numbers 1–8 or names: ``1``, ``2``, ``1,2``, ``visible,thermal``,
    ``camera_3``. Raises ``argparse.ArgumentTypeError`` naming what is allowed."""
    mask = CameraMask(0)
    items = [item.strip().lower().replace("-", "_") for item in text.split(",")]
    for item in items:
        if item.isascii() and item.isdigit() and 1 <= int(item) <= 8:
            mask |= CameraMask(1 << (int(item) - 1))
        elif item in CAMERA_NAMES:
            mask |= CAMERA_NAMES[item]
        else:
            raise argparse.ArgumentTypeError(
                f"expected camera numbers 1-8 or names ({', '.join(CAMERA_NAMES)}), "
                f"comma-separated; got {text!r}"
            )
    return mask


class Param(NamedTuple):
    """One command-line argument of a command."""

    name: str
    convert: Callable[[str], Any]
    help: str
    """Unit and range, for the command's ``--help``."""
    optional: bool = False
    """May be left out (a trailing argument; the method's default applies)."""


Build = Callable[[list[Any], Mapping[str, Any] | None], tuple[tuple[Any, ...], dict[str, Any]]]


@dataclass(frozen=True)
class CliCommand:
    """A ``send`` command: which client method it calls, with which arguments."""

    method: str
    """The :class:`GcuClient` method it calls."""
    summary: str
    """One line for ``gcu-async send --help``."""
    params: tuple[Param, ...]
    build: Build
    """The method's positional and keyword arguments from the values given."""
    together: tuple[str, ...] = ()
    """Optional arguments given all together or not at all (a box's four edges)."""
    angle_target: bool = False
    """The parameters are roll/pitch/yaw targets of an angle mode."""
    holds: bool = False
    """A mode command whose control values need packets to act (default ``--hold`` 3 s)."""
    needs_ins: bool = False
    """The GCU executes it only with valid INS data: ``send`` needs ``--aircraft``
    (the catalogue's :attr:`~gcu_async.protocol.catalogue.CatalogueEntry.needs_ins`)."""

    def parameter(self, name: str) -> inspect.Parameter | None:
        """The method's parameter ``name``, if it has one."""
        return inspect.signature(getattr(GcuClient, self.method)).parameters.get(name)

    @property
    def takes_cameras(self) -> bool:
        """The method has a ``cameras`` parameter (``--cameras`` applies)."""
        return self.parameter("cameras") is not None

    @property
    def takes_timeout(self) -> bool:
        """The method has its own ``timeout`` parameter (``--timeout`` is passed to it)."""
        return self.parameter("timeout") is not None

    def call(self, gcu: Any, values: list[Any], named: Mapping[str, Any] | None = None,
             **extra: Any) -> Any:  # fmt: skip
        """Call the method on ``gcu`` with ``values`` (the arguments in order), ``named``
        (optional arguments given by name) and the ``extra`` keyword arguments (``cameras``,
        ``timeout``); returns what it returns (a coroutine)."""
        args, kwargs = self.build(values, named)
        return getattr(gcu, self.method)(*args, **kwargs, **extra)

    def check(self, values: list[Any], named: Mapping[str, Any] | None = None,
              **extra: Any) -> None:  # fmt: skip
        """Check the arguments as the method does, with no GCU behind it: raises the same
        ``TypeError`` or :class:`~gcu_async.errors.FieldRangeError` it would, sends nothing.
        (Rate limits are checked at zoom 1x here; the method checks them again at the
        GCU's zoom.)"""
        _, kwargs = self.build(values, named)
        builder.build(self.method, **kwargs, **extra)

    def description(self) -> str:
        """The command's ``--help`` text: the summary and the method's own docstring."""
        method = getattr(GcuClient, self.method)
        names = ", ".join(p for p in inspect.signature(method).parameters if p != "self")
        doc = _plain(inspect.getdoc(method) or "")
        paragraphs = [self.summary, f"Calls GcuClient.{self.method}({names}): {doc}"]
        return "\n\n".join(textwrap.fill(p, 78) for p in paragraphs)


_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")


def _plain(doc: str) -> str:
    """A docstring as plain text: roles and double backquotes dropped, one paragraph."""
    return " ".join(_ROLE.sub(r"\1", doc).replace("``", "").split())


OPTIONS = frozenset({"cameras", "timeout"})
"""Method parameters given as options (``--cameras``, ``--timeout``), not as arguments."""
BOX_EDGES = ImageBox._fields
HOLDS = frozenset({"enter_euler_control", "enter_angle_control", "enter_fpv"})
"""Angle modes: their control values need packets to act (default ``--hold`` 3 s)."""
ANGLE_TARGET = frozenset({"enter_euler_control"})
"""Commands whose roll/pitch/yaw are absolute targets ``send`` may wait for."""
ON = "on or off (also 1/0, true/false, yes/no)"
CONVERTERS: dict[Kind, Callable[[str], Any]] = {Kind.REAL: float, Kind.INTEGER: int,
                                                Kind.SWITCH: _switch}  # fmt: skip
"""The converter of a command-line argument by its catalogue kind (choices: by name)."""


def _help(param: Parameter) -> str:
    """The ``--help`` line of a catalogue parameter: what, unit, range, default."""
    if param.kind is Kind.SWITCH:
        what = f"{ON}: {param.doc}"
    elif param.kind is Kind.CHOICE:
        what = f"{param.range_text().lower().replace(',', '')}: {param.doc}"
    else:
        bounds = " ".join(part for part in (param.range_text(), param.unit) if part)
        what = f"{bounds}: {param.doc}" if bounds else param.doc
    if param.required:
        return what
    if param.default is None:
        return f"{what} (default: the current one)"
    default = param.default
    if isinstance(default, IntEnum):
        return f"{what} (default {default.name.lower()})"
    if isinstance(default, bool):
        return f"{what} (default {'on' if default else 'off'})"
    return f"{what} (default {default})"


def _arguments(entry: CatalogueEntry) -> tuple[tuple[Param, ...], tuple[str, ...]]:
    """The command-line arguments of ``entry`` (a box as its four edges) and those given all
    together or not at all (an optional box: all four edges or none)."""
    out: list[Param] = []
    together: tuple[str, ...] = ()
    for p in entry.parameters:
        if p.name in OPTIONS:
            continue
        optional = not p.required
        if p.kind is Kind.BOX:
            together = BOX_EDGES if optional else ()
            edge = f"image fraction, 0 to 1 (step {1 / IMAGE_SCALE:g})"
            if optional:
                edge += f"; all four or none: {p.default}"
            out.extend(Param(e, float, edge, optional) for e in BOX_EDGES)
            continue
        convert = CONVERTERS[p.kind] if p.choices is None else _choice(p.choices)
        out.append(Param(p.name, convert, _help(p), optional))
    if any(a.optional and not b.optional for a, b in itertools.pairwise(out)):
        raise AssertionError(f"{entry.method}: a required argument follows an optional one")
    return tuple(out), together


def _builder(params: tuple[Param, ...]) -> Build:
    """The method's keyword arguments from the values given (a prefix of ``params``: the
    optional arguments come last); the four edges become one ``box``."""
    names = [p.name for p in params]

    def build(values: list[Any], named: Mapping[str, Any] | None = None
              ) -> tuple[tuple[Any, ...], dict[str, Any]]:  # fmt: skip
        kwargs = dict(zip(names, values, strict=False))
        for name, value in (named or {}).items():
            if name in kwargs:
                raise ValueError(f"{name}: given twice (as an argument and as --{name})")
            kwargs[name] = value
        if all(edge in kwargs for edge in BOX_EDGES):
            kwargs["box"] = tuple(kwargs.pop(edge) for edge in BOX_EDGES)
        return (), kwargs

    return build


def _command(entry: CatalogueEntry) -> CliCommand:
    params, together = _arguments(entry)
    return CliCommand(entry.method, f"0x{entry.opcode:02X}: {entry.doc}", params,
                      _builder(params), together, angle_target=entry.method in ANGLE_TARGET,
                      holds=entry.method in HOLDS, needs_ins=entry.needs_ins)  # fmt: skip


COMMANDS: dict[str, CliCommand] = {entry.cli_name: _command(entry) for entry in CATALOGUE}
"""Every ``send`` command by name (the catalogue's order, that of docs/cli.md's table)."""
