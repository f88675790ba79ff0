"""The one exception tree of gcu_async.

``GcuError`` is the root. Errors split into *local* ones (the caller passed something the
protocol cannot carry: raised before anything is sent) and *remote* ones (the peer sent
something malformed). Errors that mean "too late" or "link gone" also derive from the
builtin ``TimeoutError`` / ``ConnectionError`` so generic handlers keep working.
"""

from __future__ import annotations

import enum


class GcuError(Exception):
    """Root of every error raised by gcu_async."""


class LocalProtocolError(GcuError):
    """The caller asked for something the protocol cannot express (nothing was sent)."""


class FieldRangeError(LocalProtocolError, ValueError):
    """A value lies outside the range its wire field can carry.

    Attributes name the field, the allowed range (inclusive unless ``high_open``), the value
    as given, and its unit, so callers can report it without parsing the message.
    """

    def __init__(
        self,
        field: str,
        value: object,
        low: float,
        high: float,
        unit: str = "",
        *,
        high_open: bool = False,
        detail: str = "",
    ) -> None:
        self.field = field
        self.value = value
        self.low = low
        self.high = high
        self.unit = unit
        self.high_open = high_open
        closing = ")" if high_open else "]"
        unit_txt = f" {unit}" if unit else ""
        extra = f" ({detail})" if detail else ""
        super().__init__(
            f"{field}: {value!r} is outside the allowed range "
            f"[{_fmt(low)}, {_fmt(high)}{closing}{unit_txt}{extra}"
        )


def _fmt(x: float) -> str:
    return f"{x:.12g}" if isinstance(x, float) else str(x)


class UnsupportedCommandError(LocalProtocolError):
    """The connected pod model does not support this command (Appendix 8); nothing was sent."""

    def __init__(self, command: str, pod_model: str) -> None:
        self.command = command
        self.pod_model = pod_model
        super().__init__(f"{pod_model} does not support {command} (protocol Appendix 8)")


class ProtocolErrorReason(enum.Enum):
    """Why bytes are not a packet (:attr:`RemoteProtocolError.reason`). Only the envelope can
    make a packet invalid: a CRC-valid packet with unexpected values decodes, flagged
    (docs/client.md, "Liberal receive, strict send")."""

    SHORT = "short"
    """Fewer bytes than the shortest packet (72)."""
    HEADER = "header"
    """The first two bytes are not the header of the expected direction."""
    LENGTH = "length"
    """The length field (bytes 2–3) disagrees with the number of bytes."""
    CRC = "crc"
    """The CRC-16/XMODEM (last two bytes) does not match."""


class RemoteProtocolError(GcuError, ValueError):
    """The peer sent bytes that are not a valid packet of this protocol. ``reason`` says
    why, as a :class:`ProtocolErrorReason` (never parse the message)."""

    def __init__(self, reason: ProtocolErrorReason, message: str) -> None:
        if not isinstance(reason, ProtocolErrorReason):
            raise TypeError(f"reason: expected a ProtocolErrorReason, got {reason!r}")
        self.reason = reason
        super().__init__(message)

    def __reduce__(self) -> tuple[object, ...]:
        return (type(self), (self.reason, str(self)))


class Outcome(enum.Enum):
    """What a command that did not succeed may have done on the GCU (docs/client.md,
    "Outcomes"). Every :class:`CommandError` carries one."""

    NOT_SENT = "not sent"
    """No packet ever carried it: it did not execute and never will. Safe to retry."""
    UNKNOWN = "unknown"
    """It was sent, but no feedback proves what happened: it may have executed once (never
    twice), and packets already on their way may still make it execute later."""
    FAILED = "failed"
    """The GCU answered with a failure status for it."""


class CommandError(GcuError):
    """A command did not succeed. ``outcome`` says whether it may have executed;
    ``command`` is the command object and ``opcode`` its opcode byte."""

    def __init__(
        self, message: str, *, outcome: Outcome, opcode: int | None = None,
        command: object | None = None,
    ) -> None:  # fmt: skip
        self.outcome = outcome
        self.opcode = opcode
        self.command = command
        super().__init__(message)

    @property
    def sent(self) -> bool:
        """True if at least one packet carried the command (outcome not ``NOT_SENT``)."""
        return self.outcome is not Outcome.NOT_SENT


class LikelyCause(enum.Enum):
    """Why a command probably failed, as far as the client knows locally
    (:attr:`CommandFailed.likely_cause`). The GCU's status byte says only *that* a command
    failed; these are the protocol's own reasons the client can see from its side."""

    INS_INVALID = "INS invalid"
    """The command needs valid INS data (gaze commands) and host packets sent while it was
    pending carried the INS-valid bit (host byte 11 B0) cleared: no aircraft attitude,
    acceleration and velocity given, or older than ``aircraft_timeout``."""
    NOT_SUPPORTED = "not supported by the pod model"
    """The connected pod model does not support the command (protocol Appendix 8)."""
    ZOOM_LIMIT = "beyond the zoom limit"
    """The zoom ratio asked lies above camera 1's maximum (``GcuClient(max_zoom=…)``)."""


class CommandFailed(CommandError):
    """The GCU answered a command with a failure execution status (outcome ``FAILED``).

    ``opcode`` is the command's opcode, ``status`` the raw execution-status byte and
    ``failed_cameras`` the camera mask of the cameras that failed (zoom commands only;
    an empty mask otherwise), ``name`` the command's protocol name for the message.
    ``likely_cause`` (a :class:`LikelyCause`, or ``None``) and ``cause_detail`` (its text,
    also at the end of the message) say what the client knows locally that explains the
    failure (docs/client.md, "Why a command failed").
    """

    def __init__(
        self, opcode: int, status: int | None, failed_cameras: int = 0, *,
        command: object | None = None, name: str | None = None,
    ) -> None:  # fmt: skip
        self.status = status
        self.failed_cameras = failed_cameras
        self.likely_cause: LikelyCause | None = None
        self.cause_detail = ""
        cams = f", failed cameras 0x{failed_cameras:02X}" if failed_cameras else ""
        status_txt = "none" if status is None else f"0x{status:02X}"
        label = f"opcode 0x{opcode:02X}" if name is None else f"{name} (0x{opcode:02X})"
        super().__init__(f"{label} failed: status {status_txt}{cams}",
                         outcome=Outcome.FAILED, opcode=opcode, command=command)  # fmt: skip

    def explain(self, cause: LikelyCause, detail: str) -> None:
        """Record the likely cause (the client calls it before raising): sets
        ``likely_cause`` and ``cause_detail`` and appends the detail to the message."""
        if not isinstance(cause, LikelyCause):
            raise TypeError(f"cause: expected a LikelyCause, got {cause!r}")
        self.likely_cause = cause
        self.cause_detail = detail
        self.args = (f"{self.args[0]} (likely cause: {detail})",)


class CommandTimeout(CommandError, TimeoutError):
    """A command ran out of time: on the wire without feedback (outcome ``UNKNOWN``), or in
    the queue before it was ever sent (outcome ``NOT_SENT``)."""


class ClientStateError(GcuError, RuntimeError):
    """The client is in the wrong lifecycle state for the call: ``state`` names the state it
    is in (``"closed"``, ``"opening"``, ``"open"``, ``"closing"``)."""

    def __init__(self, message: str, *, state: str) -> None:
        self.state = state
        super().__init__(message)

    def __reduce__(self) -> tuple[object, ...]:
        return (_client_state_error, (str(self), self.state))


def _client_state_error(message: str, state: str) -> ClientStateError:
    return ClientStateError(message, state=state)


class LinkLost(GcuError, ConnectionError):
    """The link to the GCU is down (closed, silent too long, or never came up)."""


class WaitTimeout(GcuError, TimeoutError):
    """A wait on the physical world (an attitude, a zoom ratio, the link) ran out of time
    (docs/client.md, "Waiting for the gimbal, the zoom and the link"). ``what`` names the
    awaited condition, ``timeout`` the seconds waited, ``last`` the last telemetry sample
    seen (None if none arrived)."""

    def __init__(self, what: str, timeout: float, last: object | None) -> None:
        self.what = what
        self.timeout = timeout
        self.last = last
        seen = "no telemetry arrived" if last is None else f"last seen: {_describe(last)}"
        super().__init__(f"{what}: not reached within {timeout:g} s ({seen})")


def _describe(sample: object) -> str:
    """Mode, attitude and zoom of a telemetry sample, for messages (duck-typed: errors.py
    imports nothing of the package)."""
    parts = []
    status = getattr(sample, "status", None)
    if status is not None:
        a = status.attitude
        mode = str(getattr(status.mode, "name", "UNKNOWN")).lower().replace("_", " ")
        if mode == "unknown":
            mode = f"unknown (code {status.mode_raw})"
        parts.append(f"mode {mode}, roll {a.roll:g}, "
                     f"pitch {a.pitch:g}, yaw {a.yaw:g} deg")  # fmt: skip
    info = getattr(sample, "info", None)
    if info is not None:
        parts.append(f"zoom {info.camera1_zoom:g}x")
    return "; ".join(parts) or repr(sample)


class CommandLinkLost(LinkLost, CommandError):
    """A command ended because the link went down or the client closed: ``outcome`` is
    ``NOT_SENT`` if it was still queued (or the link was already down), ``UNKNOWN`` if it
    had been sent."""
