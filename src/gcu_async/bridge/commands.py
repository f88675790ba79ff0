"""Commands in, acknowledgements out: the bridge's vocabulary between MAVLink and the client.

A MAVLink command (COMMAND_LONG or COMMAND_INT) becomes a :class:`CommandIn`; the component
planners turn it into a :class:`Plan`: an immediate result (a refusal, or a reply that
needs no GCU), or a :class:`GcuCall` on the client whose outcome decides the result
(:func:`result_for`). Everything here is pure (docs/mavlink-bridge.md, "Acknowledgements").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from gcu_async.bridge._mavlink import mavlink
from gcu_async.bridge.view import Control
from gcu_async.errors import (
    CommandError,
    CommandFailed,
    LocalProtocolError,
    Outcome,
    UnsupportedCommandError,
)
from gcu_async.protocol.enums import Mode

ACCEPTED = mavlink.MAV_RESULT_ACCEPTED
TEMPORARILY_REJECTED = mavlink.MAV_RESULT_TEMPORARILY_REJECTED
DENIED = mavlink.MAV_RESULT_DENIED
UNSUPPORTED = mavlink.MAV_RESULT_UNSUPPORTED
FAILED = mavlink.MAV_RESULT_FAILED
IN_PROGRESS = mavlink.MAV_RESULT_IN_PROGRESS
CANCELLED: int = getattr(mavlink, "MAV_RESULT_CANCELLED", 6)
"""MAV_RESULT_CANCELLED (common.xml: 6; older pymavlink dialects lack the name): the
command was replaced by a newer one of its kind before it ran, and never executed."""

NO_STATUS = -1
"""COMMAND_ACK result_param2 of a FAILED command without a GCU status (timed out)."""


def command_name(command: int) -> str:
    """The MAV_CMD name of ``command`` for the log (``MAV_CMD 31999`` for an unknown id)."""
    entry = mavlink.enums["MAV_CMD"].get(command)
    return str(entry.name) if entry is not None else f"MAV_CMD {command}"


def result_name(result: int) -> str:
    """The MAV_RESULT name of ``result`` for the log (``MAV_RESULT_CANCELLED`` too)."""
    entry = mavlink.enums["MAV_RESULT"].get(result)
    if entry is not None:
        return str(entry.name)
    return "MAV_RESULT_CANCELLED" if result == CANCELLED else f"MAV_RESULT {result}"


@dataclass(frozen=True)
class CommandIn:
    """One MAVLink command: COMMAND_LONG (``frame`` None, param5/6 as sent) or COMMAND_INT
    (``frame`` given; x/y as sent, integers: latitude/longitude × 1e7 for global frames)."""

    command: int
    params: tuple[float, float, float, float, float, float, float]
    source: tuple[int, int]
    """(system id, component id) of the sender."""
    target_system: int
    target_component: int
    frame: int | None = None
    confirmation: int = 0
    """COMMAND_LONG's retransmission counter (0 the first time; COMMAND_INT has none)."""

    @classmethod
    def from_message(cls, msg: Any) -> CommandIn | None:
        """From a pymavlink COMMAND_LONG / COMMAND_INT; ``None`` for any other message."""
        kind = msg.get_type()
        source = (msg.get_srcSystem(), msg.get_srcComponent())
        if kind == "COMMAND_LONG":
            params = (msg.param1, msg.param2, msg.param3, msg.param4, msg.param5, msg.param6,
                      msg.param7)  # fmt: skip
            return cls(msg.command, params, source, msg.target_system, msg.target_component,
                       confirmation=msg.confirmation)
        if kind == "COMMAND_INT":
            params = (msg.param1, msg.param2, msg.param3, msg.param4, float(msg.x),
                      float(msg.y), msg.z)  # fmt: skip
            return cls(msg.command, params, source, msg.target_system, msg.target_component,
                       msg.frame)  # fmt: skip
        return None

    def param(self, n: int) -> float:
        """Parameter ``n`` (1–7) as a float (NaN stays NaN)."""
        return float(self.params[n - 1])

    def latitude_longitude(self) -> tuple[float, float]:
        """Param 5/6 as degrees: ×1e-7 for COMMAND_INT, as sent for COMMAND_LONG."""
        lat, lon = self.param(5), self.param(6)
        if self.frame is not None:
            return lat / 1e7, lon / 1e7
        return lat, lon


@dataclass(frozen=True)
class GcuCall:
    """A call on the client: ``await client.<method>(**kwargs)`` (or a plain call for the
    synchronous ``set_angles`` / ``set_rates`` / ``release_control``). ``mode`` is the
    working mode it establishes once confirmed; ``then`` names what the bridge does after
    a success (``"image_captured"``, ``"tracking"``)."""

    method: str
    kwargs: dict[str, Any] = field(default_factory=dict)
    mode: Mode | None = None
    then: str | None = None
    tracking_mode: int = 0


@dataclass(frozen=True)
class Plan:
    """What to do with a command: answer ``result`` now (and send ``replies`` after the
    acknowledgement), or run ``call`` and answer with its outcome."""

    result: int | None = None
    call: GcuCall | None = None
    replies: tuple[Any, ...] = ()
    reason: str = ""
    """Why a command was refused (logged)."""
    control: Control | None = None
    """New gimbal controllers, taken when the plan is accepted (CONFIGURE)."""
    camera_mode: int | None = None
    """New CAMERA_MODE reported in CAMERA_SETTINGS (SET_CAMERA_MODE)."""
    interval: tuple[int, float | None] | None = None
    """(message id, seconds) for the component's stream schedule (SET_MESSAGE_INTERVAL;
    ``math.inf`` stops the message, ``None`` restores its default)."""

    def __post_init__(self) -> None:
        if (self.result is None) == (self.call is None):
            raise ValueError("Plan: give exactly one of result= or call=")


def accept(*replies: Any) -> Plan:
    return Plan(ACCEPTED, replies=replies)


def refuse(result: int, reason: str) -> Plan:
    return Plan(result, reason=reason)


def run(call: GcuCall) -> Plan:
    return Plan(call=call)


def result_for(error: BaseException | None) -> tuple[int, int]:
    """MAV_RESULT and result_param2 for the outcome of a client call:

    ==============================================  ======================  =============
    outcome                                         result                  result_param2
    ==============================================  ======================  =============
    success (the GCU confirmed)                     ACCEPTED                0
    CommandFailed (the GCU answered "failed")       FAILED                  GCU status
    CommandError, outcome UNKNOWN (no feedback)     FAILED                  −1
    CommandError, outcome NOT_SENT (link down,      TEMPORARILY_REJECTED    0
    queue timeout: it never executed)
    UnsupportedCommandError (Appendix 8)            UNSUPPORTED             0
    FieldRangeError, TypeError, ValueError          DENIED                  0
    ==============================================  ======================  =============

    Anything else is re-raised (a bug, not an outcome)."""
    if error is None:
        return ACCEPTED, 0
    if isinstance(error, UnsupportedCommandError):
        return UNSUPPORTED, 0
    if isinstance(error, CommandFailed):
        return FAILED, NO_STATUS if error.status is None else error.status
    if isinstance(error, CommandError):
        if error.outcome is Outcome.NOT_SENT:
            return TEMPORARILY_REJECTED, 0
        return FAILED, NO_STATUS
    if isinstance(error, (LocalProtocolError, TypeError, ValueError)):
        return DENIED, 0
    raise error


def finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)
