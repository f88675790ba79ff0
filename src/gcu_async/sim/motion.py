"""Gimbal pointing: the mode machine and how the camera moves (sans-I/O).

The truth is the three relative (motor) angles roll/pitch/yaw of the camera against the aircraft;
absolute angles are derived from them plus the aircraft attitude (a small-angle sum: roll and pitch
add, yaw adds and wraps). Each mode gives every axis a *setpoint*, either absolute (stabilised in
the world) or relative (fixed to the aircraft) — docs/protocol-notes.md §5 "Control values change
meaning with the mode":

=============  =====================  =====================  ===========================
mode           roll                   pitch                  yaw
=============  =====================  =====================  ===========================
angle control  Euler angle            Euler angle            relative angle
pointing lock  level (0°)             rate → absolute        rate → absolute
pointing follow level                 rate → absolute        rate → relative (follows)
top-down       level                  −90° absolute          rate; relative if entered
                                                             from follow, else absolute
Euler control  Euler angle            Euler angle            Euler angle
gaze           level                  aims at geo target     aims at geo target
track          level                  aims at target         aims at target
FPV            relative angle         relative angle         relative angle
=============  =====================  =====================  ===========================

Rates integrate into setpoints; the motors then slew towards them at most ``max_rate`` °/s.
Simulator assumptions: relative roll within ±45°, relative pitch within [−120°, +90°],
Euler/absolute pitch setpoints within :data:`ABSOLUTE_PITCH_LIMITS`, yaw unlimited.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from gcu_async.protocol.enums import Mode
from gcu_async.protocol.host_frame_tables import ControlValues
from gcu_async.protocol.units import (
    Attitude,
    GeoPosition,
    ImageBox,
    ImagePoint,
    offset_position,
    wrap_degrees_180,
    wrap_degrees_360,
)
from gcu_async.sim.aircraft import ReceivedAircraft
from gcu_async.sim.geometry import along, direction_to, ground_hit
from gcu_async.sim.profiles import ASPECT, HORIZONTAL_FOV_DEG

ROLL, PITCH, YAW = 0, 1, 2
ROLL_LIMIT = 45.0
RELATIVE_PITCH_LIMITS = (-120.0, 90.0)
ABSOLUTE_PITCH_LIMITS = (-90.0, 90.0)
DEFAULT_MAX_RATE = 180.0
"""Default slew-rate bound, °/s (faster than the largest commandable rate, 150 °/s)."""
SETTLED_DEG = 0.05
"""A click-to-pan has arrived when both errors are below this."""
GAZE_RANGE_M = 10_000.0
GAZE_FALLBACK_M = 1_000.0
"""Gaze at a point this far along the line of sight when it meets no ground."""
MISS_FULL_SCALE = 1000


class Frame(enum.Enum):
    ABSOLUTE = "absolute"
    RELATIVE = "relative"


ABS, REL = Frame.ABSOLUTE, Frame.RELATIVE
_FRAMES: dict[Mode, tuple[Frame, Frame, Frame]] = {
    Mode.ANGLE_CONTROL: (ABS, ABS, REL),
    Mode.POINTING_LOCK: (ABS, ABS, ABS),
    Mode.POINTING_FOLLOW: (ABS, ABS, REL),
    Mode.TOP_DOWN: (ABS, ABS, ABS),
    Mode.EULER_CONTROL: (ABS, ABS, ABS),
    Mode.GAZE: (ABS, ABS, ABS),
    Mode.TRACK: (ABS, ABS, ABS),
    Mode.FPV: (REL, REL, REL),
}
LEVELLED = frozenset({
    Mode.POINTING_LOCK, Mode.POINTING_FOLLOW, Mode.TOP_DOWN, Mode.GAZE, Mode.TRACK,
})  # fmt: skip
RATE_MODES = frozenset({Mode.POINTING_LOCK, Mode.POINTING_FOLLOW, Mode.TOP_DOWN, Mode.GAZE})
ANGLE_MODES = frozenset({Mode.ANGLE_CONTROL, Mode.EULER_CONTROL, Mode.FPV})
CENTRE_MODES = frozenset({Mode.POINTING_LOCK, Mode.POINTING_FOLLOW, Mode.TOP_DOWN})
"""Modes that respond to the centre command (0x03); the others ignore it."""


@dataclass
class Setpoint:
    frame: Frame
    value: float


def field_of_view(zoom: float) -> tuple[float, float]:
    """Horizontal and vertical field of view (degrees) of camera 1 at ``zoom``."""
    h = HORIZONTAL_FOV_DEG / max(zoom, 1.0)
    return h, h / ASPECT


def image_offset(x: float, y: float, zoom: float) -> tuple[float, float]:
    """(pitch, yaw) offset in degrees of image point (x, y) (fractions, origin top-left)."""
    h, v = field_of_view(zoom)
    return -(y - 0.5) * v, (x - 0.5) * h


def _clamp(value: float, low: float, high: float) -> float:
    return min(max(value, low), high)


@dataclass
class Gimbal:
    """Mode, angles, setpoints and the work in progress (pan, track, gaze)."""

    aircraft: ReceivedAircraft
    mode: Mode = Mode.POINTING_FOLLOW
    max_rate: float = DEFAULT_MAX_RATE
    relative: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    """Relative roll, pitch, yaw (degrees): the motor angles."""
    rates: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    """Measured absolute roll, pitch, yaw rates (°/s) over the last step."""
    setpoints: list[Setpoint] = field(default_factory=list)
    control_rates: tuple[float, float, float] = (0.0, 0.0, 0.0)
    top_down_follows: bool = False
    pan: tuple[float, float] | None = None
    """Absolute (pitch, yaw) a click-to-pan is heading for."""
    track: tuple[float, float] | None = None
    """Absolute (pitch, yaw) of the tracked target."""
    track_return: Mode = Mode.POINTING_LOCK
    gaze: GeoPosition | None = None
    gaze_moving: bool = False
    miss: tuple[int, int] = (0, 0)

    def __post_init__(self) -> None:
        if not self.setpoints:
            self.enter_mode(self.mode)

    # -- views -------------------------------------------------------------------------
    def absolute(self) -> Attitude:
        """Camera Euler angles: relative angles plus the aircraft attitude."""
        a = self.aircraft.attitude
        r = self.relative
        return Attitude(a.roll + r[ROLL], a.pitch + r[PITCH], wrap_degrees_360(a.yaw + r[YAW]))

    def frames(self) -> tuple[Frame, Frame, Frame]:
        roll, pitch, yaw = _FRAMES.get(self.mode, (ABS, ABS, ABS))
        if self.mode == Mode.TOP_DOWN and self.top_down_follows:
            yaw = REL
        return roll, pitch, yaw

    def current(self, axis: int, frame: Frame) -> float:
        return self.relative[axis] if frame is REL else self.absolute()[axis]

    # -- mode changes --------------------------------------------------------------------
    def enter_mode(self, mode: Mode) -> None:
        """Switch to ``mode`` holding the present pointing (no jump), levelling roll in the
        stabilised modes and pitching to −90° in top-down."""
        previous = self.mode
        if mode == Mode.TOP_DOWN:
            self.top_down_follows = previous == Mode.POINTING_FOLLOW or (
                previous == Mode.TOP_DOWN and self.top_down_follows
            )
        self.mode = mode
        self.pan = None
        self.control_rates = (0.0, 0.0, 0.0)
        if mode != Mode.TRACK:
            self.track = None
            self.miss = (0, 0)
        if mode != Mode.GAZE:
            self.gaze = None
            self.gaze_moving = False
        frames = self.frames()
        self.setpoints = [Setpoint(f, self.current(axis, f)) for axis, f in enumerate(frames)]
        if mode in LEVELLED:
            self.setpoints[ROLL] = Setpoint(ABS, 0.0)
        if mode == Mode.TOP_DOWN:
            self.setpoints[PITCH] = Setpoint(ABS, -90.0)

    def centre(self) -> bool:
        """0x03: pitch and heading back to centre (lock/follow), heading only (top-down).
        Returns ``False`` in the modes that ignore it."""
        if self.mode not in CENTRE_MODES:
            return False
        self.pan = None
        frames = self.frames()
        if self.mode != Mode.TOP_DOWN:
            self.setpoints[PITCH] = Setpoint(ABS, 0.0)
        yaw = self.aircraft.attitude.yaw if frames[YAW] is ABS else 0.0
        self.setpoints[YAW] = Setpoint(frames[YAW], yaw)
        return True

    def click_to_pan(self, point: ImagePoint, zoom: float) -> None:
        """Click to pan: bring ``point`` to the image centre; ends in pointing-lock."""
        d_pitch, d_yaw = image_offset(point.x, point.y, zoom)
        now = self.absolute()
        self.pan = (
            _clamp(now.pitch + d_pitch, *ABSOLUTE_PITCH_LIMITS),
            wrap_degrees_360(now.yaw + d_yaw),
        )
        self.control_rates = (0.0, 0.0, 0.0)

    def start_track(self, box: ImageBox, zoom: float) -> bool:
        """Track (enter): track the target in ``box`` (fails for an empty box)."""
        if box.right <= box.left or box.bottom <= box.top:
            return False
        d_pitch, d_yaw = image_offset((box.left + box.right) / 2, (box.top + box.bottom) / 2,
                                      zoom)  # fmt: skip
        now = self.absolute()
        target = (_clamp(now.pitch + d_pitch, *ABSOLUTE_PITCH_LIMITS),
                  wrap_degrees_360(now.yaw + d_yaw))  # fmt: skip
        if self.mode != Mode.TRACK:
            self.track_return = self.mode
            self.enter_mode(Mode.TRACK)
        self.track = target
        self.setpoints[PITCH] = Setpoint(ABS, target[0])
        self.setpoints[YAW] = Setpoint(ABS, target[1])
        self._update_miss(zoom)
        return True

    def stop_track(self) -> None:
        """Track (exit): back to the mode tracking started from."""
        if self.mode == Mode.TRACK:
            self.enter_mode(self.track_return)

    def gaze_at(self, target: GeoPosition | None) -> None:
        """Gaze at coordinates (``target`` given) or gaze lock (``None``: the ground point at the
        image centre)."""
        self.enter_mode(Mode.GAZE)
        self.gaze = target if target is not None else self.point_of_view()

    def point_of_view(self) -> GeoPosition | None:
        """Where the line of sight meets the ground (or a point 1 km along it)."""
        position = self.aircraft.position
        if position is None:
            return None
        att = self.absolute()
        sight = ground_hit(att.pitch, att.yaw, self.aircraft.height, GAZE_RANGE_M)
        if sight is None:
            sight = along(att.pitch, att.yaw, GAZE_FALLBACK_M)
        return offset_position(position, sight.north, sight.east, sight.up)

    # -- inputs and time ---------------------------------------------------------------
    def control_input(self, control: ControlValues, valid: bool, zoom: float) -> None:
        """Host bytes 5–11: rates or angles per the mode (docs/protocol-notes.md §5 "Control values
        change meaning with the mode"); invalid (B2 = 0) means rate 0 and angles held. Ignored while
        a click-to-pan runs and while tracking."""
        self.control_rates = (0.0, 0.0, 0.0)
        if self.pan is not None or self.mode == Mode.TRACK:
            return
        if self.mode in RATE_MODES:
            if valid:
                rates = control.as_rates(zoom)
                self.control_rates = (rates.roll, rates.pitch, rates.yaw)
            return
        if not valid or self.mode not in ANGLE_MODES:
            return
        angles = control.as_angles()
        for axis, frame in enumerate(self.frames()):
            self.setpoints[axis] = Setpoint(frame, self._limit(axis, frame, angles[axis]))

    def step(self, dt: float, zoom: float) -> None:
        """Advance ``dt`` seconds: integrate rates, aim, slew (bounded), finish a pan."""
        if dt <= 0:
            return
        before = self.absolute()
        self._integrate(dt)
        if self.mode == Mode.GAZE:
            self._aim_gaze()
        travel = self.max_rate * dt
        for axis in range(3):
            error = self._relative_target(axis) - self.relative[axis]
            if axis == YAW:
                error = wrap_degrees_180(error)
            move = _clamp(error, -travel, travel)
            value = self.relative[axis] + move
            self.relative[axis] = wrap_degrees_180(value) if axis == YAW else value
        after = self.absolute()
        self.rates = [
            (after.roll - before.roll) / dt,
            (after.pitch - before.pitch) / dt,
            wrap_degrees_180(after.yaw - before.yaw) / dt,
        ]
        self._finish_pan()
        self._update_miss(zoom)

    def settled(self, zoom: float) -> bool:
        """True when :meth:`step` would change nothing, for any ``dt`` (the camera at
        ``zoom``): the pointing at rest. That is: no click-to-pan running, no control rate,
        every measured rate zero; in gaze, the aim where the setpoints are (and not to be
        recomputed); the setpoints within their limits; on every axis the slew's error too
        small to move the motor angle (adding it leaves the angle as it is, and so does any
        smaller move, ``max_rate * dt``: rounding is monotonic); the miss distances those of
        the present pointing."""
        if self.pan is not None or any(self.control_rates) or any(self.rates):
            return False
        if self.mode == Mode.GAZE and not self._gaze_held():
            return False
        if self.mode in RATE_MODES:  # _integrate re-limits the setpoints it moves
            for axis in (YAW,) if self.mode == Mode.TOP_DOWN else (PITCH, YAW):
                sp = self.setpoints[axis]
                if self._limit(axis, sp.frame, sp.value) != sp.value:
                    return False
        for axis in range(3):
            angle = self.relative[axis]
            error = self._relative_target(axis) - angle
            if axis == YAW:
                error = wrap_degrees_180(error)
                if wrap_degrees_180(angle) != angle:
                    return False
            if angle + error != angle:
                return False
        return self._miss(zoom) == self.miss

    # -- internals -----------------------------------------------------------------------
    def _limit(self, axis: int, frame: Frame, value: float) -> float:
        if axis == ROLL:
            return _clamp(value, -ROLL_LIMIT, ROLL_LIMIT)
        if axis == PITCH:
            limits = ABSOLUTE_PITCH_LIMITS if frame is ABS else RELATIVE_PITCH_LIMITS
            return _clamp(value, *limits)
        return wrap_degrees_360(value) if frame is ABS else wrap_degrees_180(value)

    def _integrate(self, dt: float) -> None:
        if self.mode not in RATE_MODES or self.pan is not None:
            return
        _, pitch_rate, yaw_rate = self.control_rates
        if self.mode == Mode.GAZE and (pitch_rate or yaw_rate):
            self.gaze_moving = True
        if self.mode != Mode.TOP_DOWN:
            sp = self.setpoints[PITCH]
            sp.value = self._limit(PITCH, sp.frame, sp.value + pitch_rate * dt)
        sp = self.setpoints[YAW]
        sp.value = self._limit(YAW, sp.frame, sp.value + yaw_rate * dt)

    def _aim_gaze(self) -> None:
        if self.control_rates[PITCH] or self.control_rates[YAW]:
            return  # moving by rate; re-lock when the rates return to zero
        if self.gaze_moving or self.gaze is None:
            self.gaze = self.point_of_view()
            self.gaze_moving = False
        aim = self._gaze_aim()
        if aim is not None:
            self.setpoints[PITCH], self.setpoints[YAW] = aim

    def _gaze_aim(self) -> tuple[Setpoint, Setpoint] | None:
        """The pitch and yaw setpoints that aim at the gaze point (None: no point, or no
        aircraft position to aim from)."""
        position = self.aircraft.position
        if self.gaze is None or position is None:
            return None
        pitch, yaw = direction_to(position, self.gaze)
        return Setpoint(ABS, _clamp(pitch, *ABSOLUTE_PITCH_LIMITS)), Setpoint(ABS, yaw)

    def _gaze_held(self) -> bool:
        """In gaze, the next step's aim leaves everything as it is: the point is not to be
        found again (after a move by rate, or a point of view that has appeared) and the
        setpoints are its aim already."""
        if self.gaze_moving or (self.gaze is None and self.aircraft.position is not None):
            return False
        aim = self._gaze_aim()
        return aim is None or (self.setpoints[PITCH], self.setpoints[YAW]) == aim

    def _relative_target(self, axis: int) -> float:
        sp = self.setpoints[axis]
        frame, value = sp.frame, sp.value
        if self.pan is not None and axis != ROLL:
            frame, value = ABS, self.pan[axis - 1]
        if frame is ABS:
            value -= self.aircraft.attitude[axis]
            if axis == YAW:
                value = wrap_degrees_180(value)
        return self._limit(axis, REL, value)

    def _finish_pan(self) -> None:
        if self.pan is None:
            return
        now = self.absolute()
        pitch, yaw = self.pan
        settled = abs(pitch - now.pitch) < SETTLED_DEG
        if settled and abs(wrap_degrees_180(yaw - now.yaw)) < SETTLED_DEG:
            self.enter_mode(Mode.POINTING_LOCK)
            self.setpoints[PITCH] = Setpoint(ABS, pitch)
            self.setpoints[YAW] = Setpoint(ABS, yaw)

    def _update_miss(self, zoom: float) -> None:
        self.miss = self._miss(zoom)

    def _miss(self, zoom: float) -> tuple[int, int]:
        """The miss distances (main frame bytes 8–11) the present pointing gives."""
        if self.mode != Mode.TRACK or self.track is None:
            return (0, 0)
        h, v = field_of_view(zoom)
        now = self.absolute()
        dx = wrap_degrees_180(self.track[1] - now.yaw) / (h / 2)
        dy = -(self.track[0] - now.pitch) / (v / 2)
        full = MISS_FULL_SCALE
        return (round(_clamp(dx * full, -full, full)), round(_clamp(dy * full, -full, full)))
