"""The command session, sans-I/O: scheduling, null separation, feedback matching, the
heartbeat's content, link health and the lifecycle (docs/session-contract.md, "The session
contract"; docs/client.md, "Lifecycle")."""

from gcu_async.session.config import SessionConfig
from gcu_async.session.control import ControlKind
from gcu_async.session.events import (
    Event,
    LinkDown,
    LinkUp,
    ResetLink,
    Restarted,
    TelemetrySample,
    TicketDone,
)
from gcu_async.session.health import LinkHealth
from gcu_async.session.restart import StateChange
from gcu_async.session.session import Session
from gcu_async.session.state import SessionState, SessionStats
from gcu_async.session.tickets import Ticket, TicketState

__all__ = [
    "ControlKind", "Event", "LinkDown", "LinkHealth", "LinkUp", "ResetLink", "Restarted",
    "Session", "SessionConfig", "SessionState", "SessionStats", "StateChange",
    "TelemetrySample", "Ticket", "TicketDone", "TicketState",
]  # fmt: skip
