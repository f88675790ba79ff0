"""A session's options: one frozen object, every option checked when it is made."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TypedDict

from gcu_async._checks import check_instance, check_int, check_positive, check_real
from gcu_async.errors import FieldRangeError
from gcu_async.protocol.packets import DEFAULT_VERSION
from gcu_async.session.feed import TIMEOUT_MAX

RATE_MIN_HZ = 2.0
"""Slowest heartbeat accepted (the protocol advises 30–50 Hz and must never stop)."""
RATE_MAX_HZ = 200.0


@dataclass(frozen=True, slots=True)
class SessionConfig:
    """The options of a :class:`~gcu_async.session.Session`, checked when made: a bad one
    raises ``TypeError`` or :class:`~gcu_async.errors.FieldRangeError` naming the field, its
    range and the value. Seconds are on the session's clock."""

    rate_hz: float = 50.0
    """Heartbeat rate, [2, 200] packets per second (the protocol advises 30–50)."""
    reorder_guard: float = 0.0
    """Seconds between the last packet of one opcode and the first of the next; must exceed
    how much more the link may delay one packet than another (0 on links that never
    reorder: TCP, serial)."""
    command_timeout: float = 2.0
    """Default seconds a command may spend on the wire (from its first packet to its
    feedback)."""
    queue_timeout: float = 30.0
    """Default seconds a command may wait before its first packet."""
    silence_timeout: float = 1.0
    """Seconds without a reply after which the link counts as lost; more than the heartbeat
    period."""
    control_silence: float = 0.2
    """Seconds without a reply after which control values go out invalid."""
    reply_window: float = 1.0
    """Longest round trip (GCU included) assumed possible; only used to tell which packets
    a reply may answer when no later reply settles it."""
    record_settle: float = 1.0
    """Seconds a camera may take to report a record toggle in its flags."""
    aircraft_timeout: float = 1.0
    """Seconds an aircraft part (attitude, acceleration, velocity, position) stays current
    after it was given, (0, 10]; then the packets stop claiming it
    (:mod:`~gcu_async.session.feed`)."""
    version: int = DEFAULT_VERSION
    """Protocol version byte to send (2; some devices expect 1)."""
    name: str = "gcu"
    """How errors name the link (e.g. its URL)."""

    def __post_init__(self) -> None:
        for name in OPTIONS:  # in field order: the first bad one is the error
            object.__setattr__(self, name, _check(self, name, getattr(self, name)))


def _check(config: SessionConfig, name: str, value: object) -> object:
    """``value`` of option ``name`` checked (durations as ``float``; the silence timeout
    against the rate, checked before it)."""
    if name == "rate_hz":
        return check_real(name, value, RATE_MIN_HZ, RATE_MAX_HZ, "Hz")
    if name == "reorder_guard":
        return check_positive(name, value, allow_zero=True)
    if name == "silence_timeout":
        period = 1.0 / config.rate_hz
        beyond = "must exceed the heartbeat period 1 / rate_hz: no link without packets"
        silence = check_real(name, value, period, math.inf, "s", detail=beyond)
        if silence == period:
            raise FieldRangeError(name, value, period, math.inf, "s", detail=beyond)
        return silence
    if name == "aircraft_timeout":
        timeout = check_real(name, value, 0.0, TIMEOUT_MAX, "s")
        if timeout == 0.0:
            raise FieldRangeError(name, value, 0.0, TIMEOUT_MAX, "s",
                                  detail="must be greater than 0")  # fmt: skip
        return timeout
    if name == "version":
        return check_int(name, value, 1, 2)
    if name == "name":
        return check_instance(name, value, str)
    return check_positive(name, value)


OPTIONS = tuple(f.name for f in fields(SessionConfig))
"""The option names, in order."""


class SessionOptions(TypedDict, total=False):
    """:class:`SessionConfig`'s fields as keyword arguments (``Session(**options)``)."""

    rate_hz: float
    reorder_guard: float
    command_timeout: float
    queue_timeout: float
    silence_timeout: float
    control_silence: float
    reply_window: float
    record_settle: float
    aircraft_timeout: float
    version: int
    name: str



__all__ = ["OPTIONS", "RATE_MAX_HZ", "RATE_MIN_HZ", "SessionConfig", "SessionOptions"]
