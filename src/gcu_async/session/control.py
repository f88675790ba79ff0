"""Which control values (host bytes 5–10) go out valid, and for which mode.

Control values change meaning with the mode (docs/protocol-notes.md §5 "Control values change
meaning with the mode"): the same raw numbers are Euler angles in one mode, angular rates in
another. The rule (docs/client.md, "Modes and control values"): values are sent valid only while

- the mode they were given for is the last mode the GCU confirmed (its mode command got a
  success feedback), and
- no mode-changing command is queued or in flight (commands that switch mode, and centre /
  click-to-pan / track, during which they must be invalid), and
- the latest reply reports that very mode (the pod may change mode by itself), and
- replies are arriving (none missing for ``control_silence`` seconds: packets queued towards a
  GCU that stopped reading must not steer it when it resumes).

Otherwise they go out invalid: rates 0, angles held. A mode command that fails or whose
outcome is unknown leaves no values valid until the next mode command is confirmed.
"""

from __future__ import annotations

import enum

from gcu_async._checks import check_int
from gcu_async.protocol.command_base import Command
from gcu_async.protocol.commands import COMMAND_TYPES, Track
from gcu_async.protocol.enums import Mode, Opcode, opcode_name
from gcu_async.protocol.host_frame_tables import CONTROL_ANGLE_RAW, CONTROL_RATE_RAW, ControlValues
from gcu_async.session.tickets import Ticket, TicketState


class ControlKind(enum.Enum):
    """What a mode reads from the control values."""

    ANGLES = "angles"
    RATES = "rates"
    NONE = "none"


KIND: dict[int, ControlKind] = {
    op: ControlKind(c.SCHEMA.mode.control) for op, c in COMMAND_TYPES.items() if c.SCHEMA.mode
}
"""Mode commands and what their mode reads from the control values (from the schema)."""

REPORTED: dict[int, Mode] = {
    op: c.SCHEMA.mode.mode for op, c in COMMAND_TYPES.items() if c.SCHEMA.mode
}
"""The mode byte (GCU main frame byte 5) each mode command leads to (from the schema)."""

MODE_CHANGING = frozenset(
    {*KIND, *(op for op, c in COMMAND_TYPES.items() if c.SCHEMA.changes_mode)}
)
"""Commands during which (queued or in flight) no control values are sent valid."""


def check_values(values: ControlValues, kind: ControlKind | None, opcode: int | None) -> None:
    """Control values must fit the wire and, when the mode (``opcode``) is known, its
    ``kind``: angles within ±:data:`~gcu_async.protocol.host_frame_tables.CONTROL_ANGLE_RAW`
    (0.01°), rates within ±:data:`~gcu_async.protocol.host_frame_tables.CONTROL_RATE_RAW`
    (0.1 °/s ÷ zoom); ValueError/TypeError naming the field otherwise."""
    ControlValues.check(values)
    limit = CONTROL_RATE_RAW if kind is ControlKind.RATES else CONTROL_ANGLE_RAW
    for field, raw in zip(("roll_raw", "pitch_raw", "yaw_raw"), values, strict=True):
        check_int(f"control.{field}", raw, -limit, limit)
    if kind is ControlKind.NONE and opcode is not None:
        raise ValueError(f"control: {opcode_name(opcode)} takes no control values")


class ControlState:
    """The values the user gave, the mode they belong to, and the mode commands pending."""

    def __init__(self) -> None:
        self.confirmed: int | None = None
        """Opcode of the mode command the GCU confirmed last (None: no mode known)."""
        self.values: ControlValues | None = None
        """Values for ``confirmed`` (None: sent invalid)."""
        self.command: Command | None = None
        """The command that entered ``confirmed`` (None with it)."""
        self._pending: dict[Ticket, ControlValues | None] = {}
        """Mode-changing tickets not yet final, in submission order, with the values to use
        once each is confirmed."""

    def reset(self) -> None:
        self.confirmed = None
        self.values = None
        self.command = None
        self._pending.clear()

    @property
    def pending(self) -> bool:
        return bool(self._pending)

    def submitted(self, ticket: Ticket, values: ControlValues | None) -> None:
        """Account for a submitted command; ``values`` apply once it is confirmed."""
        if ticket.opcode in MODE_CHANGING:
            self._pending[ticket] = values

    def finished(self, ticket: Ticket) -> None:
        """Account for a ticket that reached a final state."""
        if ticket not in self._pending:
            return
        values = self._pending.pop(ticket)
        state, opcode = ticket.state, ticket.opcode
        if state is TicketState.NOT_SENT:
            return  # nothing happened on the GCU
        if state is not TicketState.SUCCEEDED:
            self._forget()  # the mode is not known any more
        elif opcode == Opcode.CENTRE:
            self.values = None  # same mode; old values would steer away from the centre
        elif opcode == Opcode.CLICK_TO_PAN:
            self._forget()  # pointing-lock once the pan is done
        elif opcode == Opcode.TRACK and not (
            isinstance(ticket.command, Track) and ticket.command.enter
        ):
            self._forget()  # tracking exited: mode not reported
        else:
            self.confirmed, self.values, self.command = opcode, values, ticket.command

    def _forget(self) -> None:
        self.confirmed, self.values, self.command = None, None, None

    def target(self) -> tuple[int | None, Ticket | None]:
        """The mode new values are for: the last mode-changing command pending, else the
        confirmed mode."""
        if self._pending:
            ticket = next(reversed(self._pending))
            return ticket.opcode, ticket
        return self.confirmed, None

    def target_values(self) -> ControlValues | None:
        """The values given for :meth:`target`'s mode."""
        if self._pending:
            return self._pending[next(reversed(self._pending))]
        return self.values

    def set_values(self, values: ControlValues | None, kind: ControlKind | None) -> int | None:
        """Give new values for the current mode (see :meth:`target`); ``kind`` (if given)
        must be what that mode reads. Returns the mode's opcode (None when releasing with no
        mode known). Raises ``ValueError`` (nothing changes) when no mode takes values."""
        opcode, ticket = self.target()
        if opcode is None and values is None:
            return None
        if opcode is None:
            raise ValueError(
                "control values: no mode is confirmed or pending; call a mode command first "
                "(enter_euler_control, enter_angle_control, enter_fpv, enter_pointing_lock, "
                "enter_pointing_follow, enter_top_down, enter_gaze_lock)"
            )
        mode_kind = KIND.get(opcode, ControlKind.NONE)
        if values is not None and mode_kind is ControlKind.NONE:
            raise ValueError(f"control values: {Opcode(opcode).name} takes no control values")
        if values is not None and kind is not None and kind is not mode_kind:
            raise ValueError(
                f"control values: {Opcode(opcode).name} reads {mode_kind.value}, "
                f"not {kind.value}"
            )
        if ticket is not None:
            self._pending[ticket] = values
        else:
            self.values = values
        return opcode

    def valid(self, reported: int | None, silent: bool) -> ControlValues | None:
        """The values to send valid now, or None (send them invalid). ``reported``: the mode
        byte of the latest reply."""
        values, confirmed = self.values, self.confirmed
        if values is None or confirmed is None or self._pending or silent:
            return None
        if reported != REPORTED[confirmed]:
            return None
        return values
