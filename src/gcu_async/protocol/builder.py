"""The sans-I/O command builder: a catalogue entry and the caller's arguments give a checked
:class:`Submission` (the command, its control values, its recording intent, its timeout),
with no client, no session and no event loop.

``build("zoom_to", ratio=10.0)`` checks every argument against the entry's parameters (the
command catalogue, :mod:`gcu_async.protocol.catalogue`: the one place their ranges are
written) and returns what the client hands to its session. The client's command methods are
one-line calls of it; ``gcu-async send`` calls it to check its arguments before it opens a
link. The boundary (:mod:`gcu_async._checks`): a flag is a ``bool``, a mask or count an
``int`` (an IntFlag/IntEnum member counts as its value), a real number a finite
``int``/``float``, an enum one of its members or exact values, a box an
:class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple or list. Nothing is coerced,
clipped or wrapped. A bad argument raises ``TypeError`` or
:class:`~gcu_async.errors.FieldRangeError` whose message starts with the parameter name as
the caller wrote it (``pitch_rate``, ``box.right``) and gives the allowed range and the value.

Three arguments depend on the GCU's state, given as a :class:`Context`: an Euler angle left
``None`` keeps the camera's current one; a rate's limit (150 °/s at 1×) is divided by camera
1's current zoom; a zoom ratio is capped at the pod's ``max_zoom`` when it is known.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from types import MappingProxyType
from typing import Any, NamedTuple, TypeVar

from gcu_async._checks import check_bool, check_int, check_real
from gcu_async.errors import FieldRangeError
from gcu_async.protocol import commands as c
from gcu_async.protocol.catalogue import BY_METHOD, CatalogueEntry, Kind, Parameter
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frames import ControlValues
from gcu_async.protocol.units import Attitude, check_member, check_sequence

__all__ = ["Context", "Submission", "angles", "build", "check_sequence", "rates"]

_NT = TypeVar("_NT", bound=tuple[Any, ...])

RATE_UNIT = "deg/s"
"""The unit of a rate parameter: its limit is divided by camera 1's current zoom (the
control field carries rate × zoom)."""
ZOOM_UNIT = "x"
"""The unit of a zoom-ratio parameter: capped at :attr:`Context.max_zoom` when known."""
CAMERA_MASK = "camera mask"
"""What a :attr:`Kind.CAMERAS` parameter's error names as its unit."""


class Context(NamedTuple):
    """What the GCU last reported that some arguments depend on."""

    attitude: Attitude = Attitude(0.0, 0.0, 0.0)
    """The camera's attitude (``status.attitude``): an Euler angle left ``None`` keeps it."""
    zoom: float = 1.0
    """Camera 1's zoom ratio (>= 1): a rate's limit is divided by it."""
    max_zoom: float | None = None
    """Camera 1's largest zoom ratio when known (the client's ``max_zoom``)."""

    @classmethod
    def of(cls, status: GcuMainFrame | None, info: GcuSubFrame | None,
           max_zoom: float | None = None) -> Context:  # fmt: skip
        """The context of the latest reports (``None``: none yet: attitude zeros, zoom 1x)."""
        zoom = info.camera1_zoom if info is not None else 1.0
        attitude = status.attitude if status is not None else cls._field_defaults["attitude"]
        return cls(attitude, zoom if zoom >= 1.0 else 1.0, max_zoom)


class Submission(NamedTuple):
    """A checked command, ready for :meth:`gcu_async.session.Session.submit`."""

    command: c.Command
    control: ControlValues | None = None
    """Control values for the mode it enters (``None``: sent invalid)."""
    recording_target: bool | None = None
    """A state-checked record command: send it only if the camera's recording is not
    already this (``None``: send it unconditionally)."""
    timeout: float | None = None
    """Its own wire timeout (``None``: the client's ``command_timeout``)."""


NO_CONTEXT = Context()


def build(method: str | CatalogueEntry, context: Context = NO_CONTEXT, /,
          **arguments: object) -> Submission:  # fmt: skip
    """The :class:`Submission` of catalogue entry ``method`` (its name or the entry) called
    with ``arguments``, checked parameter by parameter in the entry's order; defaults fill
    the arguments left out. Raises ``TypeError`` for a missing or unknown argument or a
    wrong type, :class:`~gcu_async.errors.FieldRangeError` for a value out of range."""
    entry = BY_METHOD[method] if isinstance(method, str) else method
    unknown = set(arguments).difference(p.name for p in entry.parameters)
    if unknown:
        raise TypeError(f"{entry.method}() got an unexpected argument {min(unknown)!r}")
    values: dict[str, Any] = {}
    for p in CHECK_ORDER.get(entry.method, entry.parameters):
        if p.name in arguments:
            value = arguments[p.name]
        elif p.required:
            raise TypeError(f"{entry.method}() missing required argument: {p.name!r}")
        else:
            value = p.default
        values[p.name] = check(p, value, context)
    return MAKERS.get(entry.method, _positional)(entry, values, context)


CHECK_ORDER: Mapping[str, tuple[Parameter, ...]] = MappingProxyType({
    "enter_euler_control": tuple(sorted(BY_METHOD["enter_euler_control"].parameters,
                                        key=lambda p: p.name != "yaw")),
})  # fmt: skip
"""Entries whose arguments are checked in another order than the catalogue's (which one a
call with several bad arguments names; the client's methods always did it this way)."""


def check(p: Parameter, value: object, context: Context = NO_CONTEXT) -> Any:
    """``value`` of parameter ``p`` checked (:func:`build`'s rule for one argument)."""
    kind = p.kind
    if kind is Kind.REAL:
        if value is None and p.default is None:  # an angle left out keeps the current one
            value = getattr(context.attitude, p.name)
        return _real(p, value, context)
    if kind is Kind.CAMERAS or kind is Kind.INTEGER:
        assert p.low is not None
        assert p.high is not None
        unit = CAMERA_MASK if kind is Kind.CAMERAS else p.unit
        return check_int(p.name, value, int(p.low), int(p.high), unit)
    if kind is Kind.SWITCH:
        return check_bool(p.name, value)
    if kind is Kind.CHOICE:
        assert p.choices is not None
        return check_member(p.name, value, p.choices)
    if kind is Kind.BOX:
        return _box(p.name, value)
    raise AssertionError(f"{p.name}: no check for {kind}")


def _real(p: Parameter, value: object, context: Context) -> float:
    assert p.low is not None
    assert p.high is not None
    low, high, unit, detail = p.low, p.high, p.unit, ""
    if unit == RATE_UNIT:
        zoom = context.zoom
        low, high, unit = low / zoom, high / zoom, f"{RATE_UNIT} at zoom {zoom:g}x"
    elif unit == ZOOM_UNIT and context.max_zoom is not None:
        high = context.max_zoom
        detail = f"camera 1's maximum zoom is {high:g}x (max_zoom)"
    f = check_real(p.name, value, low, high, unit, high_open=p.high_open, detail=detail)
    if p.low_open and f == low:
        raise FieldRangeError(p.name, value, low, high, unit, high_open=p.high_open,
                              detail=f"must be greater than {low:g}")  # fmt: skip
    return f


def _box(name: str, value: object) -> c.ImageBox:
    """An ImageBox, a plain 4-tuple or a list of 4, each edge a fraction checked under
    ``box.<edge>``."""
    box = check_sequence(name, value, c.ImageBox)
    low, high = FRACTION.low, FRACTION.high
    assert low is not None
    assert high is not None
    return c.ImageBox(*(check_real(f"{name}.{f}", v, low, high, FRACTION.unit)
                        for f, v in zip(c.ImageBox._fields, box, strict=True)))  # fmt: skip


# -- control values outside the catalogue: set_angles, set_rates ----------------------------
FRACTION = BY_METHOD["click_to_pan"].parameter("x")
"""An image fraction (a box's edge has its range)."""
ANGLES = BY_METHOD["enter_angle_control"].parameters
"""Roll, pitch, yaw as :meth:`~gcu_async.client.GcuClient.set_angles` takes them."""
RATE = BY_METHOD["enter_pointing_lock"].parameter("pitch_rate")
"""A rate as :meth:`~gcu_async.client.GcuClient.set_rates` takes it."""


def angles(roll: object, pitch: object, yaw: object) -> ControlValues:
    """Angle control values (degrees, ±180), each checked under its name."""
    r, p, y = (_real(param, v, NO_CONTEXT) for param, v in zip(ANGLES, (roll, pitch, yaw),
                                                                strict=True))  # fmt: skip
    return ControlValues.angles(r, p, y)


def rates(context: Context, **given: object) -> ControlValues:
    """Rate control values from three rates given as ``name=value`` (roll, pitch, yaw in
    that order), each checked under the name the caller used at ``context.zoom``."""
    r, p, y = (_real(replace(RATE, name=name), v, context) for name, v in given.items())
    return ControlValues.rates(r, p, y, zoom=context.zoom)


# -- how each entry's checked values make its submission -----------------------------------
Maker = Callable[[CatalogueEntry, dict[str, Any], Context], Submission]


def _positional(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    """The command class called with the values in the catalogue's order."""
    command: Callable[..., c.Command] = entry.command
    return Submission(command(*v.values()))


def _euler(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    yaw = v["yaw"]  # [180, 360) goes out as its -180...0 equivalent
    control = ControlValues.angles(v["roll"], v["pitch"], yaw - 360.0 if yaw >= 180.0 else yaw)
    return Submission(entry.command(), control=control)


def _angles(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    return Submission(entry.command(), control=ControlValues.angles(v["roll"], v["pitch"],
                                                                   v["yaw"]))  # fmt: skip


def _rates(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    control = ControlValues.rates(0.0, v.get("pitch_rate", 0.0), v["yaw_rate"],
                                  zoom=context.zoom)  # fmt: skip
    return Submission(entry.command(), control=control)


def _keywords(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    """The command class called with the values by name (gaze_at, zoom_to...)."""
    command: Callable[..., c.Command] = entry.command
    return Submission(command(**v))


def _timeout(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    return Submission(entry.command(), timeout=v["timeout"])


def _track(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    return Submission(c.Track(True, v["box"], v["cameras"]))


def _stop_tracking(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    return Submission(c.Track(False, cameras=v["cameras"]))


def _point(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
    """``x``, ``y`` as one :class:`~gcu_async.protocol.ImagePoint`, in the place they take."""
    args = dict(v)
    point = c.ImagePoint(args.pop("x"), args.pop("y"))
    cameras = args.pop("cameras")
    command: Callable[..., c.Command] = entry.command
    return Submission(command(*args.values(), point, cameras))


def _recording(target: bool) -> Maker:
    def make(entry: CatalogueEntry, v: dict[str, Any], context: Context) -> Submission:
        return Submission(c.Record(v["cameras"]), recording_target=target)

    return make


MAKERS: Mapping[str, Maker] = MappingProxyType({
    "enter_euler_control": _euler,
    "enter_angle_control": _angles,
    "enter_fpv": _angles,
    "enter_pointing_lock": _rates,
    "enter_pointing_follow": _rates,
    "enter_top_down": _rates,
    "enter_gaze_lock": _rates,
    "gaze_at": _keywords,
    "calibrate": _timeout,
    "track": _track,
    "stop_tracking": _stop_tracking,
    "click_to_pan": _point,
    "start_recording": _recording(True),
    "stop_recording": _recording(False),
    "zoom_to": _keywords,
    "zoom_to_fraction": _keywords,
    "set_spot_temperature": _point,
})  # fmt: skip
"""The entries whose command is not their class called with the values in order."""
