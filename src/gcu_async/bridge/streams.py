"""Which messages each bridge component streams, and when (pure).

Defaults: GIMBAL_DEVICE_ATTITUDE_STATUS every 0.1 s, GIMBAL_MANAGER_STATUS every 0.2 s,
CAMERA_SETTINGS, CAMERA_CAPTURE_STATUS and CAMERA_FOV_STATUS every second, and
CAMERA_TRACKING_IMAGE_STATUS every 0.2 s *while the pod tracks* (plus one IDLE when it
stops). MAV_CMD_SET_MESSAGE_INTERVAL changes any message a component serves: −1 stops it,
0 restores the default, a positive interval (µs, at least :data:`MIN_INTERVAL_US`) streams
it at that interval — the tracking status then all the time, as QGroundControl asks while
it tracks (docs/mavlink-bridge.md, "Streams"). Heartbeats go out every second regardless.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gcu_async.bridge._mavlink import mavlink

MIN_INTERVAL_US = 10_000
"""The shortest interval the bridge streams at (100 Hz)."""
TRACKING = mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS
ATTITUDE = mavlink.MAVLINK_MSG_ID_GIMBAL_DEVICE_ATTITUDE_STATUS

DEFAULTS: dict[int, float] = {
    ATTITUDE: 0.1,
    mavlink.MAVLINK_MSG_ID_GIMBAL_MANAGER_STATUS: 0.2,
    mavlink.MAVLINK_MSG_ID_CAMERA_SETTINGS: 1.0,
    mavlink.MAVLINK_MSG_ID_CAMERA_CAPTURE_STATUS: 1.0,
    mavlink.MAVLINK_MSG_ID_CAMERA_FOV_STATUS: 1.0,
    TRACKING: 0.2,
}
"""Message id → default interval in seconds (messages not listed: not streamed)."""


def interval_from_request(value: float) -> float | None:
    """SET_MESSAGE_INTERVAL's param2 → seconds (``math.inf``: stop; ``None``: the default).
    ``ValueError`` for NaN, a fraction of a µs, or an interval shorter than
    :data:`MIN_INTERVAL_US` (−1 and 0 are the only values below it)."""
    if not math.isfinite(value) or value != int(value):
        raise ValueError(f"interval {value!r}: a whole number of microseconds, -1 or 0")
    if value == -1:
        return math.inf
    if value == 0:
        return None
    if value < MIN_INTERVAL_US:
        raise ValueError(f"interval {value:g} us: outside the allowed range "
                         f"[{MIN_INTERVAL_US}, inf) us (or -1, 0)")  # fmt: skip
    return value / 1e6


@dataclass
class Stream:
    interval: float
    """Seconds (``math.inf``: not streamed)."""
    explicit: bool = False
    """Set by SET_MESSAGE_INTERVAL (the tracking status then streams all the time)."""
    next_at: float = 0.0


class StreamSchedule:
    """Due times of the streamed messages of one component (``messages``: the ids it
    serves). ``due(now)`` returns the ids to send now and plans their next time."""

    def __init__(self, messages: frozenset[int] | set[int], start: float) -> None:
        self.messages = frozenset(messages)
        self._streams = {mid: Stream(DEFAULTS[mid], next_at=start)
                         for mid in self.messages if mid in DEFAULTS}  # fmt: skip

    def set(self, message: int, interval: float | None, now: float) -> None:
        """Stream ``message`` every ``interval`` s (``math.inf`` stops it; ``None``: the
        default). ``ValueError`` for a message this component does not serve."""
        if message not in self.messages:
            raise ValueError(f"message {message} is not served by this component")
        if interval is None:
            if message in DEFAULTS:
                self._streams[message] = Stream(DEFAULTS[message], next_at=now)
            else:
                self._streams.pop(message, None)
            return
        self._streams[message] = Stream(interval, explicit=True, next_at=now)

    def interval(self, message: int) -> float:
        """Seconds between two messages (``math.inf``: not streamed)."""
        stream = self._streams.get(message)
        return math.inf if stream is None else stream.interval

    def explicit(self, message: int) -> bool:
        stream = self._streams.get(message)
        return stream is not None and stream.explicit

    def due(self, now: float) -> list[int]:
        """The ids due at ``now``; each is planned one interval later (never in the past:
        a late loop sends once, not a burst)."""
        out = []
        for mid, stream in self._streams.items():
            if stream.interval != math.inf and now >= stream.next_at:
                out.append(mid)
                stream.next_at += stream.interval
                if stream.next_at <= now:
                    stream.next_at = now + stream.interval
        return out

    def next_time(self) -> float:
        """The earliest due time (``math.inf``: nothing streamed)."""
        return min((s.next_at for s in self._streams.values() if s.interval != math.inf),
                   default=math.inf)  # fmt: skip
