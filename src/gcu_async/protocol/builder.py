"""The sans-I/O command builder: a client method's arguments give a checked
:class:`Submission` (the command, its control values, its recording intent, its timeout),
with no client, no session and no event loop.

A command checks its own parameters when it is built (:mod:`gcu_async.protocol.commands`),
so a method that only sends its command calls the class. The functions here, one per method
that does more, add what only the method knows: the control values of the mode commands (and
calibration's timeout), checked against the parameters its catalogue entry lists; the
method's shapes (a box as a list, a point as ``x`` and ``y``, tracking's enter/exit flag, the
record commands' intent); and three arguments that depend on the GCU's state, given as a
:class:`Context`: an Euler angle left ``None`` keeps the camera's current one, a rate's limit
at 1× is divided by camera 1's current zoom, and a zoom ratio is capped at the pod's
``max_zoom`` when it is known. Each takes the context first (most need none of it).

:func:`build` does the same for a catalogue entry named by its method:
``build("zoom_to", ratio=10.0)``; ``gcu-async send`` calls it to check its arguments before
it opens a link. The boundary (:mod:`gcu_async._checks`): a flag is a ``bool``, a mask or
count an ``int`` (an IntFlag/IntEnum member counts as its value), a real number a finite
``int``/``float``, an enum one of its members or exact values, a box an
:class:`~gcu_async.protocol.ImageBox` or a plain 4-tuple or list. Nothing is coerced,
clipped or wrapped. A bad argument raises ``TypeError`` or
:class:`~gcu_async.errors.FieldRangeError` whose message starts with the parameter name as
the caller wrote it (``pitch_rate``, ``box.right``) and gives the allowed range and the value.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, NamedTuple

from gcu_async._checks import check_real, type_error
from gcu_async.errors import FieldRangeError
from gcu_async.protocol import commands as c
from gcu_async.protocol.catalogue import BY_METHOD, CatalogueEntry
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.command_fields import ZOOM_RATIO, Point, RealRange
from gcu_async.protocol.command_schema import Parameter
from gcu_async.protocol.gcu_frames import GcuMainFrame, GcuSubFrame
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.units import Attitude, ImageBox, ImagePoint, check_sequence

__all__ = ["Context", "Submission", "angles", "build", "check_sequence", "rates"]


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

    command: Command
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
    with ``arguments``; defaults fill the arguments left out. Raises ``TypeError`` for a
    missing or unknown argument or a wrong type, :class:`~gcu_async.errors.FieldRangeError`
    for a value out of range."""
    entry = BY_METHOD[method] if isinstance(method, str) else method
    unknown = set(arguments).difference(p.name for p in entry.parameters)
    if unknown:
        raise TypeError(f"{entry.method}() got an unexpected argument {min(unknown)!r}")
    values: dict[str, Any] = {}
    for p in entry.parameters:
        if p.name in arguments:
            values[p.name] = arguments[p.name]
        elif p.required:
            raise TypeError(f"{entry.method}() missing required argument: {p.name!r}")
        else:
            values[p.name] = p.default
    make = MAKERS.get(entry.method)
    if make is None:  # the class called with the method's arguments
        command: Callable[..., Command] = entry.command
        return Submission(command(**values))
    return make(context, **values)


# -- checks of what the command classes do not hold -----------------------------------------
def _explicit(command: type[Command]) -> dict[str, Parameter]:
    """The explicit parameters (control values, a timeout) of ``command``'s methods."""
    return {p.name: p for m in command.SCHEMA.methods for p in m.params or ()
            if isinstance(p, Parameter)}  # fmt: skip


def _real(p: Parameter, value: object) -> float:
    """``value`` checked against ``p``'s range."""
    assert p.low is not None
    assert p.high is not None
    f = check_real(p.name, value, p.low, p.high, p.unit, high_open=p.high_open)
    if p.low_open and f == p.low:
        raise FieldRangeError(p.name, value, p.low, p.high, p.unit, high_open=p.high_open,
                              detail=f"must be greater than {p.low:g}")  # fmt: skip
    return f


def _rate(p: Parameter, value: object, zoom: float, name: str = "") -> float:
    """A rate checked against ``p``'s limit divided by ``zoom`` (the control field carries
    rate × zoom), under ``name`` (default ``p``'s)."""
    assert p.low is not None
    assert p.high is not None
    unit = f"{p.unit} at zoom {zoom:g}x"
    return check_real(name or p.name, value, p.low / zoom, p.high / zoom, unit)


_EULER = _explicit(c.EulerControl)
_ANGLES = _explicit(c.AngleControl)
_FPV = _explicit(c.Fpv)
_TIMEOUT = _explicit(c.Calibration)["timeout"]
_RATE = _explicit(c.PointingLock)["pitch_rate"]
_POINT = next(kind for kind in c.ClickToPan.SCHEMA.params if isinstance(kind, Point)).limits
_SPOT = next(kind for kind in c.SpotTemperature.SCHEMA.params if isinstance(kind, Point)).limits
_ZOOM_RATIO = RealRange.of(ZOOM_RATIO)


def _angles(params: dict[str, Parameter], roll: object, pitch: object,
            yaw: object) -> ControlValues:  # fmt: skip
    r, p, y = (_real(params[n], v) for n, v in (("roll", roll), ("pitch", pitch), ("yaw", yaw)))
    return ControlValues.angles(r, p, y)


def _rates(command: Command, context: Context, **given: object) -> Submission:
    """A rate mode's submission: ``given`` (``pitch_rate``, ``yaw_rate``) checked at
    ``context.zoom``; the roll rate is 0."""
    params = _explicit(type(command))
    rates = {name: _rate(params[name], v, context.zoom) for name, v in given.items()}
    control = ControlValues.rates(0.0, rates.get("pitch_rate", 0.0), rates["yaw_rate"],
                                  zoom=context.zoom)  # fmt: skip
    return Submission(command, control=control)


def _point(limits: tuple[RealRange, ...], x: object, y: object) -> ImagePoint:
    """``x``, ``y`` checked under the method's names (the command names them ``point.x``)."""
    lx, ly = limits
    return ImagePoint(lx.check(x, "x"), ly.check(y, "y"))


def _number(name: str, value: float) -> float:
    """A zoom-to value as the methods take it: never ``None`` (the command reads ``None`` as
    "the other one is given"); the command checks the rest."""
    if value is None:
        raise type_error(name, "a real number", value)
    return value


def _box(box: object) -> ImageBox:
    """A box as the methods take it: an ImageBox, a plain 4-tuple or a list of 4 (JSON gives
    lists); the command checks each edge."""
    return check_sequence("box", box, ImageBox)


# -- control values outside the catalogue: set_angles, set_rates ----------------------------
def angles(roll: object, pitch: object, yaw: object) -> ControlValues:
    """Angle control values (degrees, the range of ``enter_angle_control``), each checked
    under its name."""
    return _angles(_ANGLES, roll, pitch, yaw)


def rates(context: Context, **given: object) -> ControlValues:
    """Rate control values from three rates given as ``name=value`` (roll, pitch, yaw in
    that order), each checked under the name the caller used at ``context.zoom``."""
    r, p, y = (_rate(_RATE, v, context.zoom, name) for name, v in given.items())
    return ControlValues.rates(r, p, y, zoom=context.zoom)


# -- one function per client method that does more than call its class ----------------------
def enter_euler_control(context: Context, /, *, roll: float | None, pitch: float | None,
                        yaw: float | None) -> Submission:  # fmt: skip
    """An angle left ``None`` keeps the camera's current one; a yaw past the half turn goes
    out as its negative equivalent. The yaw is checked first (a call with several bad
    angles names it)."""
    now = context.attitude
    y = _real(_EULER["yaw"], now.yaw if yaw is None else yaw)
    r = _real(_EULER["roll"], now.roll if roll is None else roll)
    p = _real(_EULER["pitch"], now.pitch if pitch is None else pitch)
    control = ControlValues.angles(r, p, y - 360.0 if y >= 180.0 else y)
    return Submission(c.EulerControl(), control=control)


def enter_angle_control(context: Context, /, *, roll: float, pitch: float,
                        yaw: float) -> Submission:  # fmt: skip
    return Submission(c.AngleControl(), control=_angles(_ANGLES, roll, pitch, yaw))


def enter_fpv(context: Context, /, *, roll: float, pitch: float, yaw: float) -> Submission:
    return Submission(c.Fpv(), control=_angles(_FPV, roll, pitch, yaw))


def enter_pointing_lock(context: Context, /, *, pitch_rate: float,
                        yaw_rate: float) -> Submission:  # fmt: skip
    return _rates(c.PointingLock(), context, pitch_rate=pitch_rate, yaw_rate=yaw_rate)


def enter_pointing_follow(context: Context, /, *, pitch_rate: float,
                          yaw_rate: float) -> Submission:  # fmt: skip
    return _rates(c.PointingFollow(), context, pitch_rate=pitch_rate, yaw_rate=yaw_rate)


def enter_top_down(context: Context, /, *, yaw_rate: float) -> Submission:
    return _rates(c.TopDown(), context, yaw_rate=yaw_rate)


def enter_gaze_lock(context: Context, /, *, pitch_rate: float, yaw_rate: float) -> Submission:
    return _rates(c.GazeLock(), context, pitch_rate=pitch_rate, yaw_rate=yaw_rate)


def calibrate(context: Context, /, *, timeout: float) -> Submission:
    return Submission(c.Calibration(), timeout=_real(_TIMEOUT, timeout))


def track(context: Context, /, *, box: ImageBox | tuple[float, float, float, float] | list[float],
          cameras: int) -> Submission:  # fmt: skip
    return Submission(c.Track(True, _box(box), cameras))


def stop_tracking(context: Context, /, *, cameras: int) -> Submission:
    return Submission(c.Track(False, cameras=cameras))


def click_to_pan(context: Context, /, *, x: float, y: float, cameras: int) -> Submission:
    return Submission(c.ClickToPan(_point(_POINT, x, y), cameras))


def start_recording(context: Context, /, *, cameras: int) -> Submission:
    return Submission(c.Record(cameras), recording_target=True)


def stop_recording(context: Context, /, *, cameras: int) -> Submission:
    return Submission(c.Record(cameras), recording_target=False)


def zoom_to(context: Context, /, *, ratio: float, cameras: int) -> Submission:
    """``ratio`` capped at ``context.max_zoom`` when it is known."""
    if context.max_zoom is not None:
        r = _ZOOM_RATIO
        check_real(r.name, ratio, r.low, context.max_zoom, r.unit,
                   detail=f"camera 1's maximum zoom is {context.max_zoom:g}x (max_zoom)")
    return Submission(c.ZoomTo(ratio=_number("ratio", ratio), cameras=cameras))


def zoom_to_fraction(context: Context, /, *, fraction: float, cameras: int) -> Submission:
    return Submission(c.ZoomTo(fraction=_number("fraction", fraction), cameras=cameras))


def set_area_temperature(context: Context, /, *, enabled: bool,
                         box: ImageBox | tuple[float, float, float, float] | list[float],
                         cameras: int) -> Submission:  # fmt: skip
    return Submission(c.AreaTemperature(enabled, _box(box), cameras))


def set_spot_temperature(context: Context, /, *, enabled: bool, x: float, y: float,
                         cameras: int) -> Submission:  # fmt: skip
    return Submission(c.SpotTemperature(enabled, _point(_SPOT, x, y), cameras))


Maker = Callable[..., Submission]
MAKERS: Mapping[str, Maker] = MappingProxyType({make.__name__: make for make in (
    enter_euler_control, enter_angle_control, enter_fpv, enter_pointing_lock,
    enter_pointing_follow, enter_top_down, enter_gaze_lock, calibrate, track, stop_tracking,
    click_to_pan, start_recording, stop_recording, zoom_to, zoom_to_fraction,
    set_area_temperature,
    set_spot_temperature,
)})  # fmt: skip
"""The methods whose submission is not their class called with their arguments, each with
its function of the same name (:func:`build` calls it with the context and the arguments by
name)."""
